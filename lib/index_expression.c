// Whole-number expressions in structure references, by recursive descent:
//
//   expression = term {("+" | "-") term}
//   term       = factor {("*" | "/") factor}
//   factor     = ("+" | "-") factor | number | name | "(" expression ")"
//
// Values are int64_t and every result is checked against +-2^31 before the next operation, so
// no operation overflows: a product of two values within 2^31 stays within 2^62.
#include "index_expression.h"

#include "model_file_text.h"
#include "springmass/base.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>

// Largest magnitude of any value along the way.
#define VALUE_LIMIT ((int64_t)1 << 31)
// Deepest nesting of parentheses and unary signs (the recursion's depth).
#define MAX_DEPTH 32
// Most bytes of a name shown in a message, as the model file's other messages quote a name or
// key (QUOTE_TEXT_BYTES, docs/model-format.md): longer ones are cut with "..." after the quote.
// A name here is ASCII letters, digits and '_', so no character is escaped or cut in two.
#define NAME_SHOWN_BYTES QUOTE_TEXT_BYTES
// The longest message, on a name whose value is not a whole number, fits the caller's buffer.
_Static_assert(sizeof "parameter ... = " - 1 + NAME_SHOWN_BYTES + SM_NUMBER_TEXT_CAPACITY - 1 +
                       sizeof " is not a whole number within 2^31" <=
                   INDEX_EXPRESSION_MESSAGE_CAPACITY,
               "INDEX_EXPRESSION_MESSAGE_CAPACITY holds the message on a name cut at NAME_SHOWN_BYTES");

typedef struct reader {
	const char* at;
	index_expression_lookup_fn lookup;
	void* context;
	char* message;
	index_expression_status status;
} reader;

static bool failed(reader* r, index_expression_status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static bool failed(reader* r, index_expression_status status, const char* format, ...)
{
	va_list args;
	va_start(args, format);
	vsnprintf(r->message, INDEX_EXPRESSION_MESSAGE_CAPACITY, format, args);
	va_end(args);
	r->status = status;
	return false;
}

static void skip_blanks(reader* r)
{
	while (*r->at == ' ' || (*r->at >= '\t' && *r->at <= '\r'))  // space, tab, LF, VT, FF, CR
		r->at++;
}

static bool is_letter(char c)
{
	return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}

static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

static bool within_limit(reader* r, int64_t value)
{
	if (value > VALUE_LIMIT || value < -VALUE_LIMIT)
		return failed(r, INDEX_EXPRESSION_INVALID, "a value beyond 2^31 in magnitude");
	return true;
}

static bool read_expression(reader* r, int depth, int64_t* value);

static bool read_factor(reader* r, int depth, int64_t* value)
{
	if (depth > MAX_DEPTH)
		return failed(r, INDEX_EXPRESSION_SYNTAX, "nested more than %d deep", MAX_DEPTH);
	skip_blanks(r);
	const char c = *r->at;
	if (c == '+' || c == '-') {
		r->at++;
		if (!read_factor(r, depth + 1, value))
			return false;
		*value = c == '-' ? -*value : *value;
		return true;
	}
	if (c == '(') {
		r->at++;
		if (!read_expression(r, depth + 1, value))
			return false;
		skip_blanks(r);
		if (*r->at != ')')
			return failed(r, INDEX_EXPRESSION_SYNTAX, "')' expected");
		r->at++;
		return true;
	}
	if (is_digit(c)) {
		int64_t v = 0;
		for (; is_digit(*r->at); r->at++) {
			v = 10 * v + (*r->at - '0');
			if (!within_limit(r, v))
				return false;
		}
		*value = v;
		return true;
	}
	if (is_letter(c)) {
		const char* name = r->at;
		while (is_letter(*r->at) || is_digit(*r->at))
			r->at++;
		const size_t length = (size_t)(r->at - name);
		const int shown = length > NAME_SHOWN_BYTES ? NAME_SHOWN_BYTES : (int)length;
		const char* cut = length > NAME_SHOWN_BYTES ? "..." : "";
		double v;
		if (!r->lookup(r->context, name, length, &v))
			return failed(r, INDEX_EXPRESSION_UNKNOWN_NAME, "no parameter named \"%.*s\"%s", shown, name,
			              cut);
		if (!(v == floor(v)) || !(fabs(v) <= (double)VALUE_LIMIT)) {
			char text[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(v, text);
			return failed(r, INDEX_EXPRESSION_NOT_WHOLE,
			              "parameter %.*s%s = %s is not a whole number within 2^31", shown, name, cut, text);
		}
		*value = (int64_t)v;
		return true;
	}
	return failed(r, INDEX_EXPRESSION_SYNTAX, "a number, a parameter or '(' expected");
}

// x / y rounded down, y != 0: C's division rounds toward zero, which differs for a negative
// quotient with a remainder.
static int64_t divide_rounding_down(int64_t x, int64_t y)
{
	const int64_t q = x / y;
	return (x % y != 0 && ((x < 0) != (y < 0))) ? q - 1 : q;
}

static bool read_term(reader* r, int depth, int64_t* value)
{
	if (!read_factor(r, depth, value))
		return false;
	for (;;) {
		skip_blanks(r);
		const char op = *r->at;
		if (op != '*' && op != '/')
			return true;
		r->at++;
		int64_t right;
		if (!read_factor(r, depth, &right))
			return false;
		if (op == '/' && right == 0)
			return failed(r, INDEX_EXPRESSION_INVALID, "division by zero");
		*value = op == '*' ? *value * right : divide_rounding_down(*value, right);
		if (!within_limit(r, *value))
			return false;
	}
}

static bool read_expression(reader* r, int depth, int64_t* value)
{
	if (!read_term(r, depth, value))
		return false;
	for (;;) {
		skip_blanks(r);
		const char op = *r->at;
		if (op != '+' && op != '-')
			return true;
		r->at++;
		int64_t right;
		if (!read_term(r, depth, &right))
			return false;
		*value = op == '+' ? *value + right : *value - right;
		if (!within_limit(r, *value))
			return false;
	}
}

index_expression_status sm_index_expression_evaluate(const char* text, index_expression_lookup_fn lookup,
                                                     void* context, int64_t* value, const char** end,
                                                     char* message)
{
	reader r = {text, lookup, context, message, INDEX_EXPRESSION_OK};
	message[0] = '\0';
	int64_t v = 0;
	if (read_expression(&r, 0, &v)) {
		skip_blanks(&r);
		if (*r.at != '\0' && *r.at != ',' && *r.at != ']')
			failed(&r, INDEX_EXPRESSION_SYNTAX, "an operator, ',' or ']' expected");
		else
			*value = v;
	}
	*end = r.at;
	return r.status;
}

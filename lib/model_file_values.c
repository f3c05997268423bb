// Model files: reading and checking values, each at a path in the document
// (`structures[2].edge.strain_stiffness`) that its messages name: numbers, or the parameters that
// stand for them (noted with what they feed and their unit, and for the messages on the element
// being read), the rules numbers obey, fields, counts, 3-vectors, booleans and names.
#include "model_file_parser.h"
#include "model_file_text.h"

#include "model_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

bool sm_parser_fail(parser* p, sm_status status, const char* path, const char* format, ...)
{
	char message[SM_ERROR_MESSAGE_CAPACITY];
	va_list args;
	va_start(args, format);
	sm_vformat_c_locale(message, sizeof message, format, args);
	va_end(args);
	if (path != NULL && path[0] != '\0')
		sm_error_set(p->err, status, "%s: %s: %s", p->doc->source, path, message);
	else
		sm_error_set(p->err, status, "%s: %s", p->doc->source, message);
	return false;
}

// Paths are built on every element read, so without printf: `path.key` and `path[index]`,
// cut to fit PATH_CAPACITY (100 + 1 + 50 + 1 and 120 + 1 + 20 + 2 bytes at most).
// Copies at most `most` characters of s (up to its end) to out; returns how many.
static size_t copy_bounded(char* out, const char* s, size_t most)
{
	size_t n = 0;
	for (; n < most && s[n] != '\0'; n++)
		out[n] = s[n];
	return n;
}

void sm_parser_child_key(char* out, const char* path, const char* key)
{
	size_t n = copy_bounded(out, path, 100);
	if (n > 0)
		out[n++] = '.';
	n += copy_bounded(out + n, key, 50);
	out[n] = '\0';
}

void sm_parser_child_index(char* out, const char* path, size_t index)
{
	size_t n = copy_bounded(out, path, 120);
	out[n++] = '[';
	char digits[24];
	int d = 0;
	do {
		digits[d++] = (char)('0' + index % 10);
		index /= 10;
	} while (index > 0);
	while (d > 0)
		out[n++] = digits[--d];
	out[n++] = ']';
	out[n] = '\0';
}

const char* sm_parser_type_name(const json_t* value)
{
	switch (json_typeof(value)) {
	case JSON_OBJECT: return "an object";
	case JSON_ARRAY: return "an array";
	case JSON_STRING: return "a string";
	case JSON_INTEGER:
	case JSON_REAL: return "a number";
	case JSON_TRUE:
	case JSON_FALSE: return "a boolean";
	case JSON_NULL: return "null";
	}
	return "a value";
}

// ---------------------------------------------------------------------------------------------
// Reading values.
// ---------------------------------------------------------------------------------------------

bool sm_parser_expect_object(parser* p, const json_t* value, const char* path)
{
	if (!json_is_object(value))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "must be an object, not %s",
		                      sm_parser_type_name(value));
	return true;
}

// Every key of obj must be one of `allowed` (NULL-terminated).
bool sm_parser_check_keys(parser* p, const json_t* obj, const char* path, const char* const* allowed)
{
	const char* key;
	json_t* value;
	json_object_foreach((json_t*)obj, key, value)
	{
		bool known = false;
		for (const char* const* a = allowed; *a != NULL && !known; a++)
			known = strcmp(*a, key) == 0;
		if (!known) {
			char list[256] = "";
			size_t used = 0;
			for (const char* const* a = allowed; *a != NULL; a++) {
				int n = snprintf(list + used, sizeof list - used, "%s%s", a == allowed ? "" : ", ", *a);
				if (n < 0 || (size_t)n >= sizeof list - used)
					break;
				used += (size_t)n;
			}
			char text[TEXT_QUOTED_CAPACITY];
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "unknown key %s (allowed here: %s)",
			                      sm_text_quoted(text, key), list);
		}
	}
	return true;
}

int32_t sm_document_find_parameter(const sm_document* doc, const char* name)
{
	return sm_name_index_find(&doc->parameter_index, name, strlen(name));
}

// Notes parameter k for messages (sm_parser_fail_naming).
void sm_parser_note_parameter(noted_parameters* noted, int32_t k)
{
	bool known = false;
	for (int n = 0; n < noted->count && !known; n++)
		known = noted->index[n] == k;
	if (!known && noted->count < NOTED_PARAMETERS)
		noted->index[noted->count++] = k;
	else if (!known)
		noted->more = true;
}

// Notes that parameter k stands for a value in `unit` (NULL: a count, an index, or a value whose
// unit the key alone does not tell): a parameter keeps a unit while every value it stands for
// has that one.
void sm_parser_note_unit(expansion* ex, int32_t k, const char* unit)
{
	const char* had = ex->parameter_units[k];
	if (had == NULL)
		ex->parameter_units[k] = unit != NULL ? unit : sm_no_single_unit();
	else if (unit == NULL || strcmp(had, unit) != 0)
		ex->parameter_units[k] = sm_no_single_unit();
}

// The unit "parameter_units" gives parameter k, or NULL.
const char* sm_parser_declared_unit(const parser* p, int32_t k)
{
	return p->doc->parameter_declared_units != NULL ? p->doc->parameter_declared_units[k] : NULL;
}

// The SI unit of the number at a key of the format, as docs/model-format.md gives it, for the
// parameters that stand for it; NULL where the key alone does not tell (atol sets both
// tolerances, m and m/s; a single spring's section is a width or an area).
static const char* key_unit(const parser* p, const char* key)
{
	static const struct {
		const char* key;
		const char* unit;
	} units[] = {
	    {"position", "m"},
	    {"velocity", "m/s"},
	    {"mass", "kg"},
	    {"rest_length", "m"},
	    {"stiffness", "N/m"},
	    {"strain_stiffness", "N"},
	    {"damping", "N.s/m"},
	    {"strain_damping", "N.s"},
	    {"break_strain", "1"},
	    {"start", "m"},
	    {"end", "m"},
	    {"mass_per_length", "kg/m"},
	    {"origin", "m"},
	    {"edge_u", "m"},
	    {"edge_v", "m"},
	    {"size", "m"},
	    {"density", "kg/m2"},
	    {"scale", "1"},
	    {"min", "m"},
	    {"max", "m"},
	    {"gravity", "m/s2"},
	    {"mass_damping", "1/s"},
	    {"stop_time", "s"},
	    {"output_interval", "s"},
	    {"rtol", "1"},
	    {"atol_position", "m"},
	    {"atol_velocity", "m/s"},
	    {"max_step", "s"},
	    {"force", "N"},
	};
	// Per section: Y s / l0 is in N/m, so Y in N/m for a width s [m], in N/m^2 for an area.
	const bool stiffness = strcmp(key, "section_stiffness") == 0;
	if (stiffness || strcmp(key, "section_damping") == 0)
		return p->section_dimension == 1   ? (stiffness ? "N/m" : "N.s/m")
		       : p->section_dimension == 2 ? (stiffness ? "N/m2" : "N.s/m2")
		                                   : NULL;
	for (size_t k = 0; k < sizeof units / sizeof units[0]; k++)
		if (strcmp(units[k].key, key) == 0)
			return units[k].unit;
	return NULL;
}

// Whether text is a decimal number, white space around it allowed: a sign, digits with a '.'
// among or before them, and an exponent ("-1.5", ".5", "1e-3"; not "2k", "1,5" or "2 * k").
static bool reads_as_number(const char* text)
{
	const char* c = text + strspn(text, " \t\n\r");
	c += *c == '-' || *c == '+';
	const size_t whole = strspn(c, "0123456789");
	c += whole;
	size_t fraction = 0;
	if (*c == '.') {
		fraction = strspn(c + 1, "0123456789");
		c += 1 + fraction;
	}
	if (whole + fraction == 0)
		return false;
	if (*c == 'e' || *c == 'E') {
		c++;
		c += *c == '-' || *c == '+';
		const size_t exponent = strspn(c, "0123456789");
		if (exponent == 0)
			return false;
		c += exponent;
	}
	c += strspn(c, " \t\n\r");
	return *c == '\0';
}

// A number, or the name of a parameter standing for one, which feeds `use` and is in `unit` (NULL:
// a count, an index, or a unit not known here). *source gets the parameter's index or -1 (source
// may be NULL).
bool sm_parser_read_number(parser* p, feeds use, const char* unit, const json_t* value, const char* path,
                           double* out, int32_t* source)
{
	if (source != NULL)
		*source = -1;
	if (json_is_number(value)) {
		*out = json_number_value(value);
		return true;
	}
	if (json_is_string(value)) {
		const int32_t k = sm_document_find_parameter(p->doc, json_string_value(value));
		char text[TEXT_QUOTED_CAPACITY];
		if (k < 0) {
			// "10" or "-1.5" is no parameter's name (names start with a letter or '_'): a number
			// in quotes. "2 * k" or "-k" is an expression, which only a structure reference's
			// indices take.
			const char* name = json_string_value(value);
			const bool expression = strpbrk(name, "+-*/()") != NULL;
			return sm_parser_fail(p, SM_ERROR_NOT_FOUND, path, "no parameter named %s%s",
			                      sm_text_quoted(text, name),
			                      reads_as_number(name) ? " (a number is written without quotes)"
			                      : expression ? " (a value is a number or a parameter's name: only the "
			                                     "indices of a structure reference take expressions)"
			                                   : "");
		}
		*out = p->parameter_values[k];
		p->ex->parameter_uses[k] |= (uint8_t)use;
		sm_parser_note_unit(p->ex, k, unit);
		const char* declared = sm_parser_declared_unit(p, k);
		if (unit != NULL && declared != NULL && strcmp(unit, declared) != 0)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
			                      "parameter %s stands for a value in %s here, but \"parameter_units\" "
			                      "gives it %s",
			                      sm_text_quoted(text, json_string_value(value)), unit, declared);
		if (source != NULL)
			*source = k;
		sm_parser_note_parameter(&p->noted, k);
		return true;
	}
	return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "must be a number or a parameter name, not %s",
	                      sm_parser_type_name(value));
}

// Describes where a value came from, for messages: "5" or "parameter k = 5" (a name longer than
// QUOTE_TEXT_BYTES cut there, as a quoted name is).
const char* sm_parser_describe(parser* p, char* buffer, size_t size, double value, int32_t source)
{
	char text[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(value, text);
	char name[TEXT_QUOTED_CAPACITY];
	if (source >= 0)
		snprintf(buffer, size, "parameter %s = %s", sm_text_cut(name, p->doc->parameter_names[source]), text);
	else
		snprintf(buffer, size, "%s", text);
	return buffer;
}

// Describes a vector so: "(parameter w = 0, 0, 0)".
const char* sm_parser_describe_vector(parser* p, char* buffer, size_t size, const double v[3],
                                      const int32_t sources[3])
{
	char text[3][DESCRIPTION_CAPACITY];
	for (int c = 0; c < 3; c++)
		sm_parser_describe(p, text[c], sizeof text[c], v[c], sources[c]);
	snprintf(buffer, size, "(%s, %s, %s)", text[0], text[1], text[2]);
	return buffer;
}

// Forgets the parameters noted so far (before reading an element).
void sm_parser_forget_parameters(parser* p)
{
	p->noted.count = 0;
	p->noted.more = false;
}

// A message naming the parameters noted: "<message> (with parameter a = 0.5 and parameter b = 2)".
bool sm_parser_fail_naming(parser* p, sm_status status, const char* path, const char* message,
                           const noted_parameters* noted)
{
	char with[SM_ERROR_MESSAGE_CAPACITY] = "";
	size_t used = 0;
	for (int n = 0; n < noted->count; n++) {
		char text[DESCRIPTION_CAPACITY];
		const char* joint = n == 0 ? " (with " : n + 1 == noted->count && !noted->more ? " and " : ", ";
		const int32_t k = noted->index[n];
		const int written = snprintf(with + used, sizeof with - used, "%s%s", joint,
		                             sm_parser_describe(p, text, sizeof text, p->parameter_values[k], k));
		if (written < 0 || (size_t)written >= sizeof with - used)
			break;
		used += (size_t)written;
	}
	if (noted->count > 0)
		snprintf(with + used, sizeof with - used, "%s)", noted->more ? " and others" : "");
	return sm_parser_fail(p, status, path, "%s%s", message, with);
}

// A builder's message on the element just read, naming the parameters its values came from.
bool sm_parser_fail_naming_parameters(parser* p, sm_status status, const char* path, const char* message)
{
	return sm_parser_fail_naming(p, status, path, message, &p->noted);
}

// v (from parameter `source`, or -1) must be finite and obey `rule`.
bool sm_parser_check_rule(parser* p, const char* path, double v, int32_t source, number_rule rule)
{
	char text[DESCRIPTION_CAPACITY];
	if (!isfinite(v))
		return sm_parser_fail(p, SM_ERROR_NOT_FINITE, path, "%s is not finite",
		                      sm_parser_describe(p, text, sizeof text, v, source));
	if ((rule == NON_NEGATIVE || rule == STEP_CAP) && v < 0.0)
		return sm_parser_fail(p, SM_ERROR_NEGATIVE, path, "%s must be >= 0",
		                      sm_parser_describe(p, text, sizeof text, v, source));
	if ((rule == POSITIVE || rule == FRACTION || rule == MASS) && !(v > 0.0))
		return sm_parser_fail(p, SM_ERROR_NEGATIVE, path, "%s must be > 0",
		                      sm_parser_describe(p, text, sizeof text, v, source));
	char least[SM_NUMBER_TEXT_CAPACITY];
	if (rule == MASS && v < SM_MIN_MASS) {
		sm_format_number(SM_MIN_MASS, least);
		return sm_parser_fail(p, SM_ERROR_NONPOSITIVE_MASS, path,
		                      "%s must be at least %s, the smallest normal double (1 / mass would overflow)",
		                      sm_parser_describe(p, text, sizeof text, v, source), least);
	}
	if (rule == FRACTION && !(v < 1.0))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s must be < 1",
		                      sm_parser_describe(p, text, sizeof text, v, source));
	// The limits in the digits the value is shown in: 2.220446049250313e-16, not 2.22045e-16,
	// which a value just above it would seem to be below.
	if (rule == FRACTION && !(v >= SM_MIN_RELATIVE_TOLERANCE)) {
		sm_format_number(SM_MIN_RELATIVE_TOLERANCE, least);
		return sm_parser_fail(
		    p, SM_ERROR_SCHEMA, path,
		    "%s must be at least %s, the machine epsilon (CVODE cannot meet a smaller relative tolerance)",
		    sm_parser_describe(p, text, sizeof text, v, source), least);
	}
	if (rule == TOLERANCE && !(v >= SM_MIN_ABSOLUTE_TOLERANCE)) {
		sm_format_number(SM_MIN_ABSOLUTE_TOLERANCE, least);
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
		                      "%s must be at least %s (CVODE's error norm overflows below)",
		                      sm_parser_describe(p, text, sizeof text, v, source), least);
	}
	if (rule == STEP_CAP && v > 0.0 && v <= SM_MAX_STEP_FLOOR) {
		sm_format_number(SM_MAX_STEP_FLOOR, least);
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
		                      "%s must be 0 (no limit) or above %s s, 1 / DBL_MAX: CVODE takes its inverse",
		                      sm_parser_describe(p, text, sizeof text, v, source), least);
	}
	return true;
}

// Optional number at obj[key] (keeps *out when absent) that must obey `rule`.
bool sm_parser_read_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                          number_rule rule, double* out, int32_t* source)
{
	int32_t dummy;
	if (source == NULL)
		source = &dummy;
	*source = -1;
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	sm_parser_child_key(sub, path, key);
	double v = 0.0;
	if (!sm_parser_read_number(p, use, key_unit(p, key), value, sub, &v, source) ||
	    !sm_parser_check_rule(p, sub, v, *source, rule))
		return false;
	*out = v;
	return true;
}

bool sm_parser_require(parser* p, const json_t* obj, const char* path, const char* key)
{
	if (json_object_get(obj, key) == NULL)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "missing required key \"%s\"", key);
	return true;
}

// A whole number in [lo, hi] (a count or an index), possibly given by a parameter.
bool sm_parser_read_count(parser* p, feeds use, const json_t* value, const char* path, int64_t lo, int64_t hi,
                          int64_t* out)
{
	double v = 0.0;
	int32_t source;
	if (!sm_parser_read_number(p, use, NULL, value, path, &v, &source))
		return false;
	char text[DESCRIPTION_CAPACITY];
	const char* declared = source >= 0 ? sm_parser_declared_unit(p, source) : NULL;
	if (declared != NULL) {
		char name[TEXT_QUOTED_CAPACITY];
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
		                      "parameter %s stands for a count or an index here, which has no unit, but "
		                      "\"parameter_units\" gives it %s",
		                      sm_text_quoted(name, p->doc->parameter_names[source]), declared);
	}
	if (!(v == floor(v)) || !(v >= (double)lo) || !(v <= (double)hi))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s must be a whole number from %lld to %lld",
		                      sm_parser_describe(p, text, sizeof text, v, source), (long long)lo,
		                      (long long)hi);
	*out = (int64_t)v;
	return true;
}

bool sm_parser_read_count_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                                int64_t lo, int64_t hi, int64_t* out)
{
	if (!sm_parser_require(p, obj, path, key))
		return false;
	char sub[PATH_CAPACITY];
	sm_parser_child_key(sub, path, key);
	return sm_parser_read_count(p, use, json_object_get(obj, key), sub, lo, hi, out);
}

// Optional 3-vector at obj[key] (keeps out when absent) whose components obey `rule`; sources
// may be NULL.
bool sm_parser_read_vector(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                           number_rule rule, double out[3], int32_t sources[3])
{
	if (sources != NULL)
		sources[0] = sources[1] = sources[2] = -1;
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	sm_parser_child_key(sub, path, key);
	if (!json_is_array(value) || json_array_size(value) != 3)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be an array of 3 numbers [x, y, z], not %s%s",
		                      sm_parser_type_name(value), json_is_array(value) ? " of another length" : "");
	for (size_t c = 0; c < 3; c++) {
		char element[PATH_CAPACITY];
		sm_parser_child_index(element, sub, c);
		int32_t source;
		double v = 0.0;
		if (!sm_parser_read_number(p, use, key_unit(p, key), json_array_get(value, c), element, &v,
		                           &source) ||
		    !sm_parser_check_rule(p, element, v, source, rule))
			return false;
		out[c] = v;
		if (sources != NULL)
			sources[c] = source;
	}
	return true;
}

bool sm_parser_read_bool(parser* p, const json_t* obj, const char* path, const char* key, bool* out)
{
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	sm_parser_child_key(sub, path, key);
	if (!json_is_boolean(value))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be true or false, not %s",
		                      sm_parser_type_name(value));
	*out = json_is_true(value);
	return true;
}

// A name: a non-empty string without control characters or line breaks, at most
// MAX_NAME_BYTES long; `identifier` also asks for a C identifier (letters, digits, '_', not
// starting with a digit).
bool sm_parser_check_name_text(parser* p, const char* s, size_t n, const char* path, bool identifier)
{
	if (n == 0 || n > MAX_NAME_BYTES)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "a name must have 1 to %d bytes (this one has %zu)",
		                      MAX_NAME_BYTES, n);
	char text[TEXT_QUOTED_CAPACITY];
	int64_t position;
	const int32_t c = sm_text_find_refused(s, sm_text_refused_in_name, &position);
	if (c >= 0)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "name %s has %s, U+%04X, at character %lld",
		                      sm_text_quoted(text, s),
		                      sm_text_is_line_break(c) ? "a line break" : "a control character", (unsigned)c,
		                      (long long)position);
	for (size_t i = 0; i < n && identifier; i++) {
		const unsigned char b = (unsigned char)s[i];
		const bool letter = (b >= 'a' && b <= 'z') || (b >= 'A' && b <= 'Z') || b == '_';
		const bool digit = b >= '0' && b <= '9';
		if (!(letter || (digit && i > 0)))
			return sm_parser_fail(
			    p, SM_ERROR_SCHEMA, path,
			    "name %s must be an identifier (letters, digits and '_', not starting with a digit)",
			    sm_text_quoted(text, s));
	}
	return true;
}

bool sm_parser_check_name(parser* p, const json_t* value, const char* path, bool identifier, const char** out)
{
	if (!json_is_string(value))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "must be a string, not %s",
		                      sm_parser_type_name(value));
	if (!sm_parser_check_name_text(p, json_string_value(value), json_string_length(value), path, identifier))
		return false;
	*out = json_string_value(value);
	return true;
}

// Whole-number expressions in a structure reference: the `n - 1` and `n / 2` of
// "cloth[n - 1, n / 2]", so that a reference follows a grid whose size is a parameter.
//
// An expression is made of whole numbers, names (the model file's parameters, whose values must
// be whole numbers), the binary operators + - * /, unary + and -, and parentheses, with the usual
// precedence (* and / before + and -, left to right), nested at most 32 deep (parentheses and unary
// signs). `/` divides and rounds down (13 / 2 is 6, -1 / 2 is -1, where C's division gives 0), so
// that (n - 1) / 2 is the middle of n particles for odd n and the one before it for even n. Every
// value along the way stays within +-2^31, so the arithmetic is exact.
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// Most bytes of a message from sm_index_expression_evaluate, NUL included: room for a name shown
// up to 80 bytes (QUOTE_TEXT_BYTES) and a number.
#define INDEX_EXPRESSION_MESSAGE_CAPACITY 192

// Looks name[0, length) up: true with its value, false for an unknown name.
typedef bool (*index_expression_lookup_fn)(void* context, const char* name, size_t length, double* value);

typedef enum index_expression_status {
	INDEX_EXPRESSION_OK = 0,
	INDEX_EXPRESSION_SYNTAX,        // not an expression: a missing operand or ')', a stray character
	INDEX_EXPRESSION_UNKNOWN_NAME,  // a name that lookup does not know
	INDEX_EXPRESSION_NOT_WHOLE,     // a name whose value is not a whole number within +-2^31
	INDEX_EXPRESSION_INVALID,       // a division by zero, or a value beyond +-2^31 along the way
} index_expression_status;

// Reads one expression from text, white space (space, tab, LF, VT, FF, CR) around its parts allowed, up to
// the first ',' or ']' outside parentheses or the end of the text; *end gets where it stopped. On success
// *value gets the expression's value. Otherwise message (INDEX_EXPRESSION_MESSAGE_CAPACITY bytes)
// says what is wrong, naming the name or value at fault ("no parameter named \"m\"",
// "parameter h = 0.5 is not a whole number", "division by zero").
index_expression_status sm_index_expression_evaluate(const char* text, index_expression_lookup_fn lookup,
                                                     void* context, int64_t* value, const char** end,
                                                     char* message);

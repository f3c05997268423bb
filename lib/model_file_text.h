// Text from a model file: what a name or a description may hold, and how a message shows it.
// The text is UTF-8; a byte that begins no well-formed character counts as one character that is
// neither a control nor a line break, and a message shows it as \xNN.
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// Most bytes of a name or key shown in a message, escapes included; then TEXT_QUOTED_CAPACITY holds
// the quotes, the ellipsis after a text cut short, and the NUL.
#define QUOTE_TEXT_BYTES 80
#define TEXT_QUOTED_CAPACITY (QUOTE_TEXT_BYTES + 6)

// Line breaks (the mandatory breaks of Unicode's line breaking algorithm, UAX #14: LF, VT, FF,
// CR, NEL, LINE SEPARATOR, PARAGRAPH SEPARATOR).
bool sm_text_is_line_break(int32_t c);

// What a name may not hold: control characters and line breaks.
bool sm_text_refused_in_name(int32_t c);

// What a description (one line of text) may not hold: line breaks and control characters but
// the tab.
bool sm_text_refused_in_description(int32_t c);

// The first character of s that `refused` refuses, or -1 if there is none; *position gets its
// position in s, counted in characters from 1.
int32_t sm_text_find_refused(const char* s, bool (*refused)(int32_t), int64_t* position);

// Line and column, from 1, of the character that ends before byte `end` of text (length bytes),
// as an editor shows them: LF, CR LF and a lone CR each end a line, and columns count characters
// (the bytes that begin a UTF-8 character). For the JSON parser's error position it gives the
// parser's own line and column wherever lines end in LF; a position at a line end, whichever its
// kind, is at column 0 of the next line.
void sm_text_position(const char* text, size_t length, size_t end, int* line, int* column);

// The column, from 1, of the character that begins at line[bytes], where line is the start of its
// line: the characters (bytes that begin a UTF-8 character) before it, plus 1. Reads the `bytes`
// bytes before it, so a caller placing many things on one line finds the line's columns once.
int64_t sm_text_column(const char* line, size_t bytes);

// Writes s into out as a JSON string's contents would hold it (`"` and `\` escaped; control
// characters, line separators and the zero-width and bidirectional characters, which a terminal
// would act on or not show, as \uXXXX; a malformed byte as \xNN), at most `most` bytes and whole
// characters only, NUL-terminated (out has room for most + 1). Returns whether all of s fitted.
bool sm_text_escape(char* out, size_t most, const char* s);

// s for a message without quotes around it: only the characters a terminal would act on or not
// show escaped (as sm_text_escape does them), at most `most` bytes, NUL-terminated.
void sm_text_shown(char* out, size_t most, const char* s);

// The most bytes a file's name takes in a message (sm_text_shown_path), "..." included: a model
// file's and an OBJ file's together leave 231 of a message's SM_ERROR_MESSAGE_CAPACITY - 1 bytes
// to say where and what is wrong (an element's path, a line and column, and the longest reason: an
// OBJ file's unknown statement quoted up to 80 bytes, about 200 bytes in all).
#define SM_TEXT_SHOWN_PATH_BYTES 140

// A file's path for a message: escaped as sm_text_shown does, and one longer than
// SM_TEXT_SHOWN_PATH_BYTES shown by its end ("..." and the longest tail of whole characters that
// fits, the file's own name last), NUL-terminated.
void sm_text_shown_path(char out[SM_TEXT_SHOWN_PATH_BYTES + 1], const char* path);

// "s" for a message: escaped, and cut after QUOTE_TEXT_BYTES at a character boundary with "..."
// after the closing quote. Returns out.
const char* sm_text_quoted(char out[TEXT_QUOTED_CAPACITY], const char* s);

// s for a message without quotes around it, as a parameter's name is shown ("parameter k = 5"):
// escaped as sm_text_shown does, and cut after QUOTE_TEXT_BYTES at a character boundary with "..."
// after it, as sm_text_quoted cuts. Returns out.
const char* sm_text_cut(char out[TEXT_QUOTED_CAPACITY], const char* s);

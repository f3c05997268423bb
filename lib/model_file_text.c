// Text from a model file: what a name or a description may hold, and how a message shows it
// (model_file_text.h).
#include "model_file_text.h"

#include "springmass/model_file.h"

#include <stdio.h>
#include <string.h>

// The UTF-8 character at s (n > 0 bytes left): its code point, and in *bytes its length. A byte
// that begins no well-formed character (RFC 3629: no overlong forms, no surrogates, nothing
// above U+10FFFF) gives -1 and *bytes = 1. (The JSON parser has checked the strings of a file;
// this also serves text that has not passed through it.)
static int32_t decode_utf8(const unsigned char* s, size_t n, size_t* bytes)
{
	*bytes = 1;
	if (s[0] < 0x80)
		return s[0];
	// F8 - FF begin no character (RFC 3629 ends at F4): a four-byte form keeps only the low three
	// bits of its first byte, so that F8 80 80 80 and above would pass for F0 80 80 80.
	const size_t length = s[0] >= 0xf8 ? 0 : s[0] >= 0xf0 ? 4 : s[0] >= 0xe0 ? 3 : s[0] >= 0xc0 ? 2 : 0;
	static const int32_t least[5] = {0, 0, 0x80, 0x800, 0x10000};
	if (length == 0 || length > n)
		return -1;
	int32_t c = s[0] & (0x7f >> length);
	for (size_t k = 1; k < length; k++) {
		if ((s[k] & 0xc0) != 0x80)
			return -1;
		c = (c << 6) | (s[k] & 0x3f);
	}
	if (c < least[length] || c > 0x10ffff || (c >= 0xd800 && c <= 0xdfff))
		return -1;
	*bytes = length;
	return c;
}

// Control characters: C0, DEL and C1 (Unicode general category Cc).
static bool is_control(int32_t c)
{
	return c < 0x20 || (c >= 0x7f && c < 0xa0);
}

bool sm_text_is_line_break(int32_t c)
{
	return (c >= '\n' && c <= '\r') || c == 0x85 || c == 0x2028 || c == 0x2029;
}

bool sm_text_refused_in_name(int32_t c)
{
	return is_control(c) || sm_text_is_line_break(c);
}

bool sm_text_refused_in_description(int32_t c)
{
	return (is_control(c) && c != '\t') || sm_text_is_line_break(c);
}

int32_t sm_text_find_refused(const char* s, bool (*refused)(int32_t), int64_t* position)
{
	const unsigned char* u = (const unsigned char*)s;
	const size_t n = strlen(s);
	*position = 0;
	for (size_t at = 0; at < n;) {
		size_t bytes;
		const int32_t c = decode_utf8(u + at, n - at, &bytes);
		++*position;
		if (c >= 0 && refused(c))
			return c;
		at += bytes;
	}
	return -1;
}

// Characters a message shows escaped, since a terminal would act on them or show nothing:
// control characters, the line and paragraph separators U+2028 and U+2029, the zero-width
// characters U+200B - U+200D, U+2060 - U+2064 (the word joiner and the invisible mathematical
// operators) and U+FEFF, and the bidirectional controls (U+061C, U+200E, U+200F, U+202A -
// U+202E, U+2066 - U+2069), which reorder the text around them.
static bool shown_escaped(int32_t c)
{
	return is_control(c) || c == 0x061c || (c >= 0x200b && c <= 0x200f) || (c >= 0x2028 && c <= 0x202e) ||
	       (c >= 0x2060 && c <= 0x2064) || (c >= 0x2066 && c <= 0x2069) || c == 0xfeff;
}

void sm_text_position(const char* text, size_t length, size_t end, int* line, int* column)
{
	*line = 1;
	*column = 0;
	for (size_t i = 0; i < end && i < length; i++) {
		const unsigned char c = (unsigned char)text[i];
		// The CR of a CR LF is part of the line end, counted at its LF; but where the position
		// falls between the two, the line end has begun, as it has after an LF.
		const bool crlf = c == '\r' && i + 1 < length && text[i + 1] == '\n';
		if (c == '\n' || (c == '\r' && (!crlf || i + 1 == end))) {
			++*line;
			*column = 0;
		} else if (c != '\r' && (c & 0xc0) != 0x80) {
			++*column;
		}
	}
}

int64_t sm_text_column(const char* line, size_t bytes)
{
	int64_t column = 1;
	for (size_t k = 0; k < bytes; k++)
		column += ((unsigned char)line[k] & 0xc0) != 0x80;
	return column;
}

// sm_text_escape, or with quotes false sm_text_shown.
static bool escape(char* out, size_t most, const char* s, bool quotes)
{
	const unsigned char* u = (const unsigned char*)s;
	const size_t n = strlen(s);
	size_t used = 0;
	for (size_t at = 0; at < n;) {
		size_t bytes;
		const int32_t c = decode_utf8(u + at, n - at, &bytes);
		char escaped[8];
		const char* piece = escaped;
		size_t length;
		if (c < 0)
			length = (size_t)snprintf(escaped, sizeof escaped, "\\x%02x", u[at]);
		else if (quotes && (c == '"' || c == '\\'))
			length = (size_t)snprintf(escaped, sizeof escaped, "\\%c", (char)c);
		else if (shown_escaped(c))
			length = (size_t)snprintf(escaped, sizeof escaped, "\\u%04x", (unsigned)c);
		else {
			piece = s + at;
			length = bytes;
		}
		if (used + length > most) {
			out[used] = '\0';
			return false;
		}
		memcpy(out + used, piece, length);
		used += length;
		at += bytes;
	}
	out[used] = '\0';
	return true;
}

bool sm_text_escape(char* out, size_t most, const char* s)
{
	return escape(out, most, s, true);
}

void sm_text_shown(char* out, size_t most, const char* s)
{
	escape(out, most, s, false);
}

// The bytes of the character at u (of n bytes) as sm_text_shown writes it; *bytes, its own.
static size_t shown_bytes(const unsigned char* u, size_t n, size_t* bytes)
{
	const int32_t c = decode_utf8(u, n, bytes);
	return c < 0 ? 4 : shown_escaped(c) ? 6 : *bytes;
}

void sm_text_shown_path(char out[SM_TEXT_SHOWN_PATH_BYTES + 1], const char* path)
{
	const unsigned char* u = (const unsigned char*)path;
	const size_t n = strlen(path);
	size_t total = 0, bytes;
	for (size_t at = 0; at < n; at += bytes)
		total += shown_bytes(u + at, n - at, &bytes);
	if (total <= SM_TEXT_SHOWN_PATH_BYTES) {
		escape(out, SM_TEXT_SHOWN_PATH_BYTES, path, false);
		return;
	}
	// Characters dropped from the start until the rest fits after "...".
	size_t at = 0;
	for (; at < n && total > SM_TEXT_SHOWN_PATH_BYTES - 3; at += bytes)
		total -= shown_bytes(u + at, n - at, &bytes);
	memcpy(out, "...", 3);
	escape(out + 3, SM_TEXT_SHOWN_PATH_BYTES - 3, path + at, false);
}

void sm_text_for_terminal(char* out, const char* text)
{
	if (out == NULL)
		return;
	if (text == NULL)
		text = "";
	// Every byte of text becomes at most 6 (a control character's \uXXXX), so all of it fits.
	escape(out, SM_TERMINAL_TEXT_CAPACITY(strlen(text)) - 1, text, false);
}

const char* sm_text_quoted(char out[TEXT_QUOTED_CAPACITY], const char* s)
{
	out[0] = '"';
	const bool whole = sm_text_escape(out + 1, QUOTE_TEXT_BYTES, s);
	strcat(out, whole ? "\"" : "\"...");
	return out;
}

const char* sm_text_cut(char out[TEXT_QUOTED_CAPACITY], const char* s)
{
	if (!escape(out, QUOTE_TEXT_BYTES, s, false))
		strcat(out, "...");
	return out;
}

// springmass FMU: a growing text buffer for the files the packager writes (modelDescription.xml,
// documentation/index.html) and the parameter lines an FMU carries.
//
// Appending never fails loudly: a failed allocation marks the buffer failed, later appends do
// nothing, and the writer checks `failed` once at the end.
#pragma once

#include <stdbool.h>
#include <stddef.h>

typedef struct fmu_text {
	char* data;     ///< NUL-terminated once anything was appended
	size_t length;  ///< bytes before the NUL
	size_t capacity;
	bool failed;  ///< an allocation failed: data is incomplete
} fmu_text;

/// Appends n bytes of s.
void fmu_text_append(fmu_text* t, const char* s, size_t n);

/// Appends the NUL-terminated s.
void fmu_text_append_string(fmu_text* t, const char* s);

/// Appends printf-formatted text (in the caller's locale: format numbers with sm_format_number).
void fmu_text_appendf(fmu_text* t, const char* fmt, ...) __attribute__((format(printf, 2, 3)));

/// Appends s escaped for XML and HTML text and attribute values (& < > " ', a tab as "&#9;"); a
/// line break becomes a space, other control characters are dropped, and the noncharacters U+FFFE
/// and U+FFFF, which XML cannot hold, become U+FFFD. NULL appends nothing.
void fmu_text_append_escaped(fmu_text* t, const char* s);

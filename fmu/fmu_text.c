// springmass FMU: the growing text buffer (see fmu_text.h).
#include "fmu_text.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fmu_text_append(fmu_text* t, const char* s, size_t n)
{
	if (t->failed)
		return;
	if (t->length + n + 1 > t->capacity) {
		size_t capacity = t->capacity ? t->capacity : 4096;
		while (capacity < t->length + n + 1)
			capacity *= 2;
		char* grown = realloc(t->data, capacity);
		if (!grown) {
			t->failed = true;
			return;
		}
		t->data = grown;
		t->capacity = capacity;
	}
	memcpy(t->data + t->length, s, n);
	t->length += n;
	t->data[t->length] = '\0';
}

void fmu_text_append_string(fmu_text* t, const char* s)
{
	fmu_text_append(t, s, strlen(s));
}

void fmu_text_appendf(fmu_text* t, const char* fmt, ...)
{
	char small[512];
	va_list args;
	va_start(args, fmt);
	int n = vsnprintf(small, sizeof small, fmt, args);
	va_end(args);
	if (n < 0) {
		t->failed = true;
		return;
	}
	if ((size_t)n < sizeof small) {
		fmu_text_append(t, small, (size_t)n);
		return;
	}
	char* big = malloc((size_t)n + 1);
	if (!big) {
		t->failed = true;
		return;
	}
	va_start(args, fmt);
	vsnprintf(big, (size_t)n + 1, fmt, args);
	va_end(args);
	fmu_text_append(t, big, (size_t)n);
	free(big);
}

// XML 1.0 (2.2, Char) has no way to write the noncharacters U+FFFE and U+FFFF, not even as
// character references, which a model file's names and descriptions may hold (UTF-8 EF BF BE and
// EF BF BF): each is written as the replacement character U+FFFD. A tab is written as a reference,
// since a parser reads a literal tab in an attribute value as a space (3.3.3).
void fmu_text_append_escaped(fmu_text* t, const char* s)
{
	for (; s && *s; ++s) {
		switch (*s) {
		case '&': fmu_text_append_string(t, "&amp;"); break;
		case '<': fmu_text_append_string(t, "&lt;"); break;
		case '>': fmu_text_append_string(t, "&gt;"); break;
		case '"': fmu_text_append_string(t, "&quot;"); break;
		case '\'': fmu_text_append_string(t, "&apos;"); break;
		case '\n': fmu_text_append_string(t, " "); break;
		case '\t': fmu_text_append_string(t, "&#9;"); break;
		default:
			if ((unsigned char)s[0] == 0xef && (unsigned char)s[1] == 0xbf &&
			    ((unsigned char)s[2] == 0xbe || (unsigned char)s[2] == 0xbf)) {
				fmu_text_append_string(t, "\xef\xbf\xbd");
				s += 2;
			} else if ((unsigned char)*s >= 0x20) {
				fmu_text_append(t, s, 1);
			}
			break;
		}
	}
}

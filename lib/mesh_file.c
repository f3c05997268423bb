// Triangle meshes from Wavefront OBJ text (see mesh_file.h and docs/model-format.md).
//
// A statement is a keyword and its arguments, separated by blanks (space, tab, VT, FF), up to the
// end of the line; a backslash just before a line end continues the statement on the next line,
// and `#` begins a comment that runs to the end of the line. The text is read twice: the first
// pass checks every statement and counts the vertices and triangles (so that a file past the
// limits is refused before anything is allocated, and a face may name a vertex that comes later
// in the file), the second fills arrays of exactly that size.
#define _POSIX_C_SOURCE 200809L  // newlocale, uselocale

#include "mesh_file.h"

#include "c_locale.h"

#include "model_file_text.h"
#include "springmass/model.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// A word of the text: bytes [start, start + length) on line `line`, whose first byte follows the
// line's start `line_start` (for its column).
typedef struct token {
	size_t start, length;
	int32_t line;
	size_t line_start;
} token;

typedef struct reader {
	const char* text;
	size_t length, at;
	int32_t line;  // of the byte at `at`, from 1
	size_t line_start;
	mesh_file* fill;         // NULL in the first pass, which counts
	int64_t vertices;        // read so far
	int64_t triangles;       // made so far
	int64_t total_vertices;  // of the whole file (second pass), or -1
	int64_t max_vertices, max_triangles;
	// The first failure.
	sm_status status;
	int* line_out;
	int* column_out;
	char* message;
} reader;

static bool is_blank(char c)
{
	return c == ' ' || c == '\t' || c == '\v' || c == '\f';
}

static bool is_line_end(const reader* r, size_t at)
{
	return at < r->length && (r->text[at] == '\n' || r->text[at] == '\r');
}

// Moves past the line end at r->at (LF, CR LF or CR) to the start of the next line.
static void pass_line_end(reader* r)
{
	r->at += r->text[r->at] == '\r' && r->at + 1 < r->length && r->text[r->at + 1] == '\n' ? 2 : 1;
	r->line++;
	r->line_start = r->at;
}

// A backslash that continues the statement on the next line (or ends the text).
static bool is_continuation(const reader* r, size_t at)
{
	return r->text[at] == '\\' && (at + 1 == r->length || is_line_end(r, at + 1));
}

static void skip_blanks(reader* r)
{
	while (r->at < r->length) {
		if (is_blank(r->text[r->at]))
			r->at++;
		else if (is_continuation(r, r->at)) {
			r->at++;
			if (r->at < r->length)
				pass_line_end(r);
		} else
			break;
	}
}

// Whether the statement ends at r->at: the end of the text or of the line, or a comment.
static bool at_statement_end(const reader* r)
{
	return r->at == r->length || is_line_end(r, r->at) || r->text[r->at] == '#';
}

// The next word of the statement, if there is one.
static bool next_token(reader* r, token* t)
{
	skip_blanks(r);
	if (at_statement_end(r))
		return false;
	t->start = r->at;
	t->line = r->line;
	t->line_start = r->line_start;
	while (r->at < r->length && !is_blank(r->text[r->at]) && !at_statement_end(r) &&
	       !is_continuation(r, r->at))
		r->at++;
	t->length = r->at - t->start;
	return true;
}

// Past the rest of the line (a comment) and its end.
static void finish_line(reader* r)
{
	while (r->at < r->length && !is_line_end(r, r->at))
		r->at++;
	if (r->at < r->length)
		pass_line_end(r);
}

// The column of a token's first character: the characters (bytes that begin a UTF-8 character)
// before it on its line, plus 1. It reads the line up to the token: once per statement, not once
// per triangle of a face, or a face of many vertices after a long run of blanks would read them
// again for each of its triangles.
static int32_t column_of(const reader* r, const token* t)
{
	const int64_t column = sm_text_column(r->text + t->line_start, t->start - t->line_start);
	return column > INT32_MAX ? INT32_MAX : (int32_t)column;
}

static bool fail(reader* r, sm_status status, const token* t, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static bool fail(reader* r, sm_status status, const token* t, const char* format, ...)
{
	r->status = status;
	*r->line_out = t != NULL ? t->line : 0;
	*r->column_out = t != NULL ? column_of(r, t) : 0;
	va_list args;
	va_start(args, format);
	vsnprintf(r->message, MESH_FILE_MESSAGE_CAPACITY, format, args);
	va_end(args);
	return false;
}

// A token for a message: escaped (a terminal would act on control characters), quoted, cut
// after QUOTE_TEXT_BYTES.
static const char* quoted(const reader* r, const token* t, char out[TEXT_QUOTED_CAPACITY])
{
	char word[QUOTE_TEXT_BYTES + 8];
	const size_t n = t->length < sizeof word - 1 ? t->length : sizeof word - 1;
	memcpy(word, r->text + t->start, n);
	word[n] = '\0';
	return sm_text_quoted(out, word);
}

static bool is_word(const reader* r, const token* t, const char* word)
{
	return strlen(word) == t->length && memcmp(r->text + t->start, word, t->length) == 0;
}

static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

// A decimal number, as a model file writes one but with an optional '+', a point without digits
// on one side ("1.", ".5") allowed: [+-] digits [. digits] [(e|E) [+-] digits]. Neither
// hexadecimal numbers nor infinities or NaN, which strtod would read. SM_ERROR_SYNTAX for another
// word, SM_ERROR_OUT_OF_MEMORY for a long number without the memory to read it.
static sm_status read_decimal(const reader* r, const token* t, double* value)
{
	const char* s = r->text + t->start;
	const size_t n = t->length;
	size_t k = 0, digits = 0;
	k += k < n && (s[k] == '+' || s[k] == '-');
	for (; k < n && is_digit(s[k]); k++)
		digits++;
	if (k < n && s[k] == '.')
		for (k++; k < n && is_digit(s[k]); k++)
			digits++;
	if (digits == 0)
		return SM_ERROR_SYNTAX;
	if (k < n && (s[k] == 'e' || s[k] == 'E')) {
		k++;
		k += k < n && (s[k] == '+' || s[k] == '-');
		size_t exponent = 0;
		for (; k < n && is_digit(s[k]); k++)
			exponent++;
		if (exponent == 0)
			return SM_ERROR_SYNTAX;
	}
	if (k != n)
		return SM_ERROR_SYNTAX;
	// strtod reads up to a NUL, which the text need not have after the word.
	char small[64];
	char* copy = n < sizeof small ? small : malloc(n + 1);
	if (copy == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	memcpy(copy, s, n);
	copy[n] = '\0';
	*value = strtod(copy, NULL);  // in the C locale (sm_mesh_file_parse)
	if (copy != small)
		free(copy);
	return SM_OK;
}

// "v x y z", "v x y z w" or "v x y z r g b" (a colour, as MeshLab writes one); only x, y and z
// are kept.
static bool read_vertex(reader* r, const token* keyword)
{
	double x[3] = {0.0, 0.0, 0.0};
	int count = 0;
	token t;
	char text[TEXT_QUOTED_CAPACITY];
	while (next_token(r, &t)) {
		double value = 0.0;
		const sm_status number = read_decimal(r, &t, &value);
		if (number == SM_ERROR_OUT_OF_MEMORY)
			return fail(r, number, &t, "out of memory for a number of %zu characters", t.length);
		if (number != SM_OK)
			return fail(r, number, &t, "%s is not a number", quoted(r, &t, text));
		if (count < 3 && !isfinite(value))
			return fail(r, SM_ERROR_NOT_FINITE, &t, "coordinate %s is beyond the largest double",
			            quoted(r, &t, text));
		if (count < 3)
			x[count] = value;
		if (count < 7)
			count++;
	}
	if (count != 3 && count != 4 && count != 6)
		return fail(r, SM_ERROR_SYNTAX, keyword,
		            "a vertex has 3 coordinates x y z, then a weight w or a colour r g b at most, not %d%s "
		            "numbers",
		            count, count > 6 ? " or more" : "");
	if (r->vertices >= r->max_vertices)
		return fail(r, SM_ERROR_SCHEMA, keyword,
		            "more than %lld vertices, the most a model's particles allow",
		            (long long)r->max_vertices);
	if (r->fill != NULL) {
		memcpy(r->fill->vertices + 3 * r->vertices, x, sizeof x);
		r->fill->vertex_place[2 * r->vertices] = keyword->line;
		r->fill->vertex_place[2 * r->vertices + 1] = column_of(r, keyword);
	}
	r->vertices++;
	return true;
}

// Most characters of a face's index shown in a message, "..." after them.
#define INDEX_SHOWN_BYTES 24

// A whole number at s[*k] (of n bytes): an optional sign and at least one digit; *k moves past it.
// Values past 2^40, far past any index, are held as 2^40 and more, without overflow.
static bool read_integer(const char* s, size_t n, size_t* k, int64_t* value)
{
	const bool negative = *k < n && s[*k] == '-';
	*k += *k < n && (s[*k] == '+' || s[*k] == '-');
	int64_t v = 0;
	size_t digits = 0;
	for (; *k < n && is_digit(s[*k]); (*k)++, digits++)
		if (v < ((int64_t)1 << 40))
			v = 10 * v + (s[*k] - '0');
	*value = negative ? -v : v;
	return digits > 0;
}

// The vertex a face names, "i", "i/t", "i//n" or "i/t/n" (t and n, a texture coordinate and a
// normal, are read and dropped), as an index from 0: i from 1, or counting back from -1, the last
// vertex read before it.
static bool read_corner(reader* r, const token* t, int64_t* index)
{
	const char* s = r->text + t->start;
	const size_t n = t->length;
	size_t k = 0;
	int64_t i, dropped;
	bool well_formed = read_integer(s, n, &k, &i);
	// The index as written, for a message: its value is held at 2^40 and more past that.
	const int written = (int)(k < INDEX_SHOWN_BYTES ? k : INDEX_SHOWN_BYTES);
	const char* cut = k > INDEX_SHOWN_BYTES ? "..." : "";
	if (well_formed && k < n) {
		well_formed = s[k] == '/' && k + 1 < n;
		k++;
		if (well_formed && s[k] != '/')
			well_formed = read_integer(s, n, &k, &dropped);
		if (well_formed && k < n) {
			well_formed = s[k] == '/';
			k++;
			well_formed = well_formed && read_integer(s, n, &k, &dropped);
		}
	}
	char text[TEXT_QUOTED_CAPACITY];
	if (!well_formed || k != n)
		return fail(r, SM_ERROR_SYNTAX, t, "%s is not a face's vertex (i, i/t, i//n or i/t/n, whole numbers)",
		            quoted(r, t, text));
	if (i == 0)
		return fail(r, SM_ERROR_PARTICLE_INDEX, t,
		            "face index 0: vertices are numbered from 1, or back from -1 for the last one read");
	if (i < 0 && -i > r->vertices)
		return fail(r, SM_ERROR_PARTICLE_INDEX, t,
		            "face index %.*s%s counts back past the first vertex (%lld vertices come before it)",
		            written, s, cut, (long long)r->vertices);
	if (i > 0 && r->total_vertices >= 0 && i > r->total_vertices)
		return fail(r, SM_ERROR_PARTICLE_INDEX, t, "face index %.*s%s is past the %lld vertices", written, s,
		            cut, (long long)r->total_vertices);
	*index = i > 0 ? i - 1 : r->vertices + i;
	return true;
}

// "f v1 v2 v3 ...": a polygon of at least 3 vertices, cut into triangles as a fan from its first
// vertex: (v1, v2, v3), (v1, v3, v4), ...
static bool read_face(reader* r, const token* keyword)
{
	int64_t corners = 0, first = -1, previous = -1;
	// Where each of its triangles is in the file (second pass).
	const int32_t column = r->fill != NULL ? column_of(r, keyword) : 0;
	token t;
	while (next_token(r, &t)) {
		int64_t index = 0;
		if (!read_corner(r, &t, &index))
			return false;
		if (corners >= 2 && r->triangles >= r->max_triangles)
			return fail(r, SM_ERROR_SCHEMA, keyword,
			            "more than %lld triangles (faces cut into triangles), the most a mesh may have",
			            (long long)r->max_triangles);
		if (corners >= 2 && r->fill != NULL) {
			int32_t* triangle = r->fill->triangles + 3 * r->triangles;
			triangle[0] = (int32_t)first;
			triangle[1] = (int32_t)previous;
			triangle[2] = (int32_t)index;
			r->fill->triangle_place[2 * r->triangles] = keyword->line;
			r->fill->triangle_place[2 * r->triangles + 1] = column;
		}
		if (corners >= 2)
			r->triangles++;
		if (corners == 0)
			first = index;
		previous = index;
		corners++;
	}
	if (corners < 3)
		return fail(r, SM_ERROR_SYNTAX, keyword, "a face needs at least 3 vertices, not %lld",
		            (long long)corners);
	return true;
}

// Statements that carry no geometry a mesh holds, read and dropped: texture coordinates, normals,
// parameter-space vertices, names, groups, smoothing and merging groups, materials, polylines,
// points, and display and rendering attributes.
static bool is_ignored(const reader* r, const token* t)
{
	static const char* const ignored[] = {
	    "vt",       "vn",         "vp",        "o",     "g",      "s",      "mg",    "usemtl",
	    "mtllib",   "l",          "p",         "lod",   "maplib", "usemap", "bevel", "c_interp",
	    "d_interp", "shadow_obj", "trace_obj", "ctech", "stech",  NULL};
	for (const char* const* k = ignored; *k != NULL; k++)
		if (is_word(r, t, *k))
			return true;
	return false;
}

// Free-form curves and surfaces, and the statements that read other files or run commands:
// refused, since dropping them would drop geometry.
static bool is_free_form(const reader* r, const token* t)
{
	static const char* const free_form[] = {"cstype", "deg",  "bmat", "step", "curv", "curv2",
	                                        "surf",   "parm", "trim", "hole", "scrv", "sp",
	                                        "end",    "con",  "call", "csh",  NULL};
	for (const char* const* k = free_form; *k != NULL; k++)
		if (is_word(r, t, *k))
			return true;
	return false;
}

static bool read_statements(reader* r)
{
	r->at = 0;
	r->line = 1;
	r->line_start = 0;
	r->vertices = r->triangles = 0;
	// A UTF-8 byte-order mark may open the text, as it may a model file's.
	if (r->length >= 3 && memcmp(r->text, "\xef\xbb\xbf", 3) == 0)
		r->at = r->line_start = 3;
	while (r->at < r->length) {
		token keyword;
		if (next_token(r, &keyword)) {
			char text[TEXT_QUOTED_CAPACITY];
			bool ok = true;
			if (is_word(r, &keyword, "v"))
				ok = read_vertex(r, &keyword);
			else if (is_word(r, &keyword, "f"))
				ok = read_face(r, &keyword);
			else if (is_ignored(r, &keyword)) {
				token rest;
				while (next_token(r, &rest))
					;
			} else if (is_free_form(r, &keyword))
				ok = fail(r, SM_ERROR_SYNTAX, &keyword,
				          "%s: free-form curves and surfaces are not read (export the mesh as polygons)",
				          quoted(r, &keyword, text));
			else
				ok = fail(
				    r, SM_ERROR_SYNTAX, &keyword,
				    "unknown statement %s (a mesh is read from v and f; vt, vn, o, g, s, usemtl, mtllib, l "
				    "and the like are skipped)",
				    quoted(r, &keyword, text));
			if (!ok)
				return false;
		}
		finish_line(r);
	}
	return true;
}

void sm_mesh_file_free(mesh_file* mesh)
{
	if (mesh == NULL)
		return;
	free(mesh->vertices);
	free(mesh->triangles);
	free(mesh->vertex_place);
	free(mesh->triangle_place);
	memset(mesh, 0, sizeof *mesh);
}

sm_status sm_mesh_file_parse(const char* text, size_t length, int64_t max_vertices, int64_t max_triangles,
                             mesh_file* out, int* line, int* column, char* message)
{
	memset(out, 0, sizeof *out);
	*line = *column = 0;
	message[0] = '\0';
	reader r = {.text = text,
	            .length = length,
	            .total_vertices = -1,
	            .max_vertices = max_vertices,
	            .max_triangles = max_triangles,
	            .status = SM_OK,
	            .line_out = line,
	            .column_out = column,
	            .message = message};
	const char* nul = memchr(text, '\0', length);
	if (nul != NULL) {
		sm_text_position(text, length, (size_t)(nul - text) + 1, line, column);
		snprintf(message, MESH_FILE_MESSAGE_CAPACITY, "a NUL byte (an OBJ file is text)");
		return SM_ERROR_SYNTAX;
	}
	// Numbers are read in the C locale, whatever LC_NUMERIC the calling thread has (a decimal comma
	// would cut "0.5" at its point).
	const sm_c_locale_scope scope = sm_enter_c_locale();
	if (!sm_c_locale_entered(scope)) {
		snprintf(message, MESH_FILE_MESSAGE_CAPACITY, "out of memory for the C locale");
		return SM_ERROR_OUT_OF_MEMORY;
	}
	bool ok = read_statements(&r);
	if (ok && r.triangles == 0)
		ok = fail(&r, SM_ERROR_SCHEMA, NULL, "no face (f), so no triangle: a mesh needs at least one");
	if (ok) {
		// Room for one at least: a face of a file without vertices is refused in the second pass,
		// at its first index.
		const size_t nv = r.vertices > 0 ? (size_t)r.vertices : 1, nt = (size_t)r.triangles;
		out->vertices = malloc(3 * nv * sizeof(double));
		out->vertex_place = malloc(2 * nv * sizeof(int32_t));
		out->triangles = malloc(3 * nt * sizeof(int32_t));
		out->triangle_place = malloc(2 * nt * sizeof(int32_t));
		if (out->vertices == NULL || out->vertex_place == NULL || out->triangles == NULL ||
		    out->triangle_place == NULL)
			ok = fail(&r, SM_ERROR_OUT_OF_MEMORY, NULL, "out of memory for %lld vertices and %zu triangles",
			          (long long)r.vertices, nt);
	}
	if (ok) {
		r.fill = out;
		r.total_vertices = r.vertices;
		ok = read_statements(&r);
		out->vertex_count = (int32_t)r.vertices;
		out->triangle_count = (int32_t)r.triangles;
	}
	sm_leave_c_locale(scope);
	if (!ok) {
		sm_mesh_file_free(out);
		return r.status;
	}
	return SM_OK;
}

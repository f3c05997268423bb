// Model files: parsing with jansson, validation and evaluation into a model (the format is
// documented in docs/model-format.md).
//
// Loading parses the text into a JSON tree, reads the parameters, then evaluates the tree
// ("expands" it) into a model, the particles' names, the ports and the settings. Every value is
// checked where it is read, so a message can name its path in the document
// (`springs[3].b: no particle named "bobb"`), the value and the rule. Unknown keys are errors.
// Every failure frees what was made so far; nothing is left half-built.
#define _POSIX_C_SOURCE 200809L  // open, fstat, read

#include "c_locale.h"
#include "index_expression.h"
#include "model_file_internal.h"
#include "model_file_text.h"

#include "model_internal.h"
#include "structures_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

// Largest model file read from disk [bytes].
#define MAX_FILE_BYTES ((long)1 << 30)
// Room for a path in the document such as `structures[2].edge.strain_stiffness`.
#define PATH_CAPACITY 160
// Longest particle, port or parameter name [bytes].
#define MAX_NAME_BYTES 200
// Room for "parameter NAME = VALUE" (describe) with the longest name [bytes].
#define DESCRIPTION_CAPACITY (MAX_NAME_BYTES + 64)
// Longest structure name [bytes]. A structure's particles are named name[i], name[row,column]
// or name[row,column,layer] (saved files name every particle so), with indices below
// SM_DOCUMENT_MAX_ELEMENTS, at most 7 digits each: the suffix has at most 3 * 7 + 4 = 25 bytes,
// and every particle's name stays within MAX_NAME_BYTES, as any name in a file must.
#define MAX_STRUCTURE_NAME_BYTES (MAX_NAME_BYTES - 25)
_Static_assert(SM_DOCUMENT_MAX_ELEMENTS <= 10000000,
               "the indices of a structure's particles have at most 7 digits");

// The parameters the values of one element (a structure, a spring) came from, for messages of
// the builders, which see the values but not where they came from: the first few, and whether
// there were more.
#define NOTED_PARAMETERS 4

typedef struct noted_parameters {
	int32_t index[NOTED_PARAMETERS];
	int count;
	bool more;
} noted_parameters;

typedef struct parser {
	const sm_document* doc;
	const double* parameter_values;
	sm_error* err;
	expansion* ex;
	noted_parameters noted;  // of the element being read
	// What a per-section constant multiplies in the structure being read: 1 a width [m] (sheet,
	// mesh), 2 an area [m^2] (block); 0 unknown (a single spring's section is either).
	int section_dimension;
} parser;

// Records the first failure: "<source>: <path>: <message>".
static bool fail(parser* p, sm_status status, const char* path, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static bool fail(parser* p, sm_status status, const char* path, const char* format, ...)
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

static void child_key(char* out, const char* path, const char* key)
{
	size_t n = copy_bounded(out, path, 100);
	if (n > 0)
		out[n++] = '.';
	n += copy_bounded(out + n, key, 50);
	out[n] = '\0';
}

static void child_index(char* out, const char* path, size_t index)
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

static const char* type_name(const json_t* value)
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

static bool expect_object(parser* p, const json_t* value, const char* path)
{
	if (!json_is_object(value))
		return fail(p, SM_ERROR_SCHEMA, path, "must be an object, not %s", type_name(value));
	return true;
}

// Every key of obj must be one of `allowed` (NULL-terminated).
static bool check_keys(parser* p, const json_t* obj, const char* path, const char* const* allowed)
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
			return fail(p, SM_ERROR_SCHEMA, path, "unknown key %s (allowed here: %s)",
			            sm_text_quoted(text, key), list);
		}
	}
	return true;
}

static int32_t find_parameter(const sm_document* doc, const char* name)
{
	return sm_name_index_find(&doc->parameter_index, name, strlen(name));
}

// What a value read feeds (sm_parameter_use), recorded for the parameter that gave it, if any.
typedef enum feeds {
	FEEDS_CONSTANTS = SM_PARAMETER_CONSTANTS,
	FEEDS_STATE = SM_PARAMETER_INITIAL_STATE,
	FEEDS_MOTION = SM_PARAMETER_MOTION,
	FEEDS_COUNTS = SM_PARAMETER_COUNTS,
	FEEDS_SETTINGS = SM_PARAMETER_SETTINGS,
	FEEDS_SPRING_KINDS = SM_PARAMETER_SPRING_KINDS,
	FEEDS_REFERENCES = SM_PARAMETER_PARTICLE_REFERENCES,
} feeds;

// Notes parameter k for messages (fail_naming).
static void note_parameter(noted_parameters* noted, int32_t k)
{
	bool known = false;
	for (int n = 0; n < noted->count && !known; n++)
		known = noted->index[n] == k;
	if (!known && noted->count < NOTED_PARAMETERS)
		noted->index[noted->count++] = k;
	else if (!known)
		noted->more = true;
}

// The unit of parameters that stand for values of different units, or for counts and indices.
static const char no_single_unit[] = "";

// Notes that parameter k stands for a value in `unit` (NULL: a count, an index, or a value whose
// unit the key alone does not tell): a parameter keeps a unit while every value it stands for
// has that one.
static void note_unit(expansion* ex, int32_t k, const char* unit)
{
	const char* had = ex->parameter_units[k];
	if (had == NULL)
		ex->parameter_units[k] = unit != NULL ? unit : no_single_unit;
	else if (unit == NULL || strcmp(had, unit) != 0)
		ex->parameter_units[k] = no_single_unit;
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

// A number, or the name of a parameter standing for one, which feeds `use` and is in `unit` (NULL:
// a count, an index, or a unit not known here). *source gets the parameter's index or -1 (source
// may be NULL).
static bool read_number(parser* p, feeds use, const char* unit, const json_t* value, const char* path,
                        double* out, int32_t* source)
{
	if (source != NULL)
		*source = -1;
	if (json_is_number(value)) {
		*out = json_number_value(value);
		return true;
	}
	if (json_is_string(value)) {
		const int32_t k = find_parameter(p->doc, json_string_value(value));
		char text[TEXT_QUOTED_CAPACITY];
		if (k < 0) {
			// "10" or "-1.5" is no parameter's name (names start with a letter or '_'): a number
			// in quotes.
			const char* name = json_string_value(value);
			const char* digit = name + (name[0] == '-' || name[0] == '+');
			digit += digit[0] == '.';
			const bool numeric = digit[0] >= '0' && digit[0] <= '9';
			return fail(p, SM_ERROR_NOT_FOUND, path, "no parameter named %s%s", sm_text_quoted(text, name),
			            numeric ? " (a number is written without quotes)" : "");
		}
		*out = p->parameter_values[k];
		p->ex->parameter_uses[k] |= (uint8_t)use;
		note_unit(p->ex, k, unit);
		if (source != NULL)
			*source = k;
		note_parameter(&p->noted, k);
		return true;
	}
	return fail(p, SM_ERROR_SCHEMA, path, "must be a number or a parameter name, not %s", type_name(value));
}

// Describes where a value came from, for messages: "5" or "parameter k = 5".
static const char* describe(parser* p, char* buffer, size_t size, double value, int32_t source)
{
	char text[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(value, text);
	if (source >= 0)
		snprintf(buffer, size, "parameter %s = %s", p->doc->parameter_names[source], text);
	else
		snprintf(buffer, size, "%s", text);
	return buffer;
}

// Describes a vector so: "(parameter w = 0, 0, 0)".
static const char* describe_vector(parser* p, char* buffer, size_t size, const double v[3],
                                   const int32_t sources[3])
{
	char text[3][DESCRIPTION_CAPACITY];
	for (int c = 0; c < 3; c++)
		describe(p, text[c], sizeof text[c], v[c], sources[c]);
	snprintf(buffer, size, "(%s, %s, %s)", text[0], text[1], text[2]);
	return buffer;
}

// Forgets the parameters noted so far (before reading an element).
static void forget_parameters(parser* p)
{
	p->noted.count = 0;
	p->noted.more = false;
}

// A message naming the parameters noted: "<message> (with parameter a = 0.5 and parameter b = 2)".
static bool fail_naming(parser* p, sm_status status, const char* path, const char* message,
                        const noted_parameters* noted)
{
	char with[SM_ERROR_MESSAGE_CAPACITY] = "";
	size_t used = 0;
	for (int n = 0; n < noted->count; n++) {
		char text[DESCRIPTION_CAPACITY];
		const char* joint = n == 0 ? " (with " : n + 1 == noted->count && !noted->more ? " and " : ", ";
		const int32_t k = noted->index[n];
		const int written = snprintf(with + used, sizeof with - used, "%s%s", joint,
		                             describe(p, text, sizeof text, p->parameter_values[k], k));
		if (written < 0 || (size_t)written >= sizeof with - used)
			break;
		used += (size_t)written;
	}
	if (noted->count > 0)
		snprintf(with + used, sizeof with - used, "%s)", noted->more ? " and others" : "");
	return fail(p, status, path, "%s%s", message, with);
}

// A builder's message on the element just read, naming the parameters its values came from.
static bool fail_naming_parameters(parser* p, sm_status status, const char* path, const char* message)
{
	return fail_naming(p, status, path, message, &p->noted);
}

// FRACTION: > 0 and < 1, and at least SM_MIN_RELATIVE_TOLERANCE (a relative tolerance: CVODE
// cannot meet one below the machine epsilon, simulation.h); TOLERANCE: an absolute tolerance, at
// least SM_MIN_ABSOLUTE_TOLERANCE; MASS: a particle's mass, at least SM_MIN_MASS; STEP_CAP: a
// largest step, 0 (none) or one above SM_MAX_STEP_FLOOR (simulation.h).
typedef enum number_rule {
	ANY_FINITE,
	NON_NEGATIVE,
	POSITIVE,
	FRACTION,
	TOLERANCE,
	MASS,
	STEP_CAP
} number_rule;

// v (from parameter `source`, or -1) must be finite and obey `rule`.
static bool check_rule(parser* p, const char* path, double v, int32_t source, number_rule rule)
{
	char text[DESCRIPTION_CAPACITY];
	if (!isfinite(v))
		return fail(p, SM_ERROR_NOT_FINITE, path, "%s is not finite",
		            describe(p, text, sizeof text, v, source));
	if ((rule == NON_NEGATIVE || rule == STEP_CAP) && v < 0.0)
		return fail(p, SM_ERROR_NEGATIVE, path, "%s must be >= 0", describe(p, text, sizeof text, v, source));
	if ((rule == POSITIVE || rule == FRACTION || rule == MASS) && !(v > 0.0))
		return fail(p, SM_ERROR_NEGATIVE, path, "%s must be > 0", describe(p, text, sizeof text, v, source));
	char least[SM_NUMBER_TEXT_CAPACITY];
	if (rule == MASS && v < SM_MIN_MASS) {
		sm_format_number(SM_MIN_MASS, least);
		return fail(p, SM_ERROR_NONPOSITIVE_MASS, path,
		            "%s must be at least %s, the smallest normal double (1 / mass would overflow)",
		            describe(p, text, sizeof text, v, source), least);
	}
	if (rule == FRACTION && !(v < 1.0))
		return fail(p, SM_ERROR_SCHEMA, path, "%s must be < 1", describe(p, text, sizeof text, v, source));
	// The limits in the digits the value is shown in: 2.220446049250313e-16, not 2.22045e-16,
	// which a value just above it would seem to be below.
	if (rule == FRACTION && !(v >= SM_MIN_RELATIVE_TOLERANCE)) {
		sm_format_number(SM_MIN_RELATIVE_TOLERANCE, least);
		return fail(
		    p, SM_ERROR_SCHEMA, path,
		    "%s must be at least %s, the machine epsilon (CVODE cannot meet a smaller relative tolerance)",
		    describe(p, text, sizeof text, v, source), least);
	}
	if (rule == TOLERANCE && !(v >= SM_MIN_ABSOLUTE_TOLERANCE)) {
		sm_format_number(SM_MIN_ABSOLUTE_TOLERANCE, least);
		return fail(p, SM_ERROR_SCHEMA, path, "%s must be at least %s (CVODE's error norm overflows below)",
		            describe(p, text, sizeof text, v, source), least);
	}
	if (rule == STEP_CAP && v > 0.0 && v <= SM_MAX_STEP_FLOOR) {
		sm_format_number(SM_MAX_STEP_FLOOR, least);
		return fail(p, SM_ERROR_SCHEMA, path,
		            "%s must be 0 (no limit) or above %s s, 1 / DBL_MAX: CVODE takes its inverse",
		            describe(p, text, sizeof text, v, source), least);
	}
	return true;
}

// Optional number at obj[key] (keeps *out when absent) that must obey `rule`.
static bool read_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
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
	child_key(sub, path, key);
	double v = 0.0;
	if (!read_number(p, use, key_unit(p, key), value, sub, &v, source) ||
	    !check_rule(p, sub, v, *source, rule))
		return false;
	*out = v;
	return true;
}

static bool require(parser* p, const json_t* obj, const char* path, const char* key)
{
	if (json_object_get(obj, key) == NULL)
		return fail(p, SM_ERROR_SCHEMA, path, "missing required key \"%s\"", key);
	return true;
}

// A whole number in [lo, hi] (a count or an index), possibly given by a parameter.
static bool read_count(parser* p, feeds use, const json_t* value, const char* path, int64_t lo, int64_t hi,
                       int64_t* out)
{
	double v = 0.0;
	int32_t source;
	if (!read_number(p, use, NULL, value, path, &v, &source))
		return false;
	char text[DESCRIPTION_CAPACITY];
	if (!(v == floor(v)) || !(v >= (double)lo) || !(v <= (double)hi))
		return fail(p, SM_ERROR_SCHEMA, path, "%s must be a whole number from %lld to %lld",
		            describe(p, text, sizeof text, v, source), (long long)lo, (long long)hi);
	*out = (int64_t)v;
	return true;
}

static bool read_count_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                             int64_t lo, int64_t hi, int64_t* out)
{
	if (!require(p, obj, path, key))
		return false;
	char sub[PATH_CAPACITY];
	child_key(sub, path, key);
	return read_count(p, use, json_object_get(obj, key), sub, lo, hi, out);
}

// Optional 3-vector at obj[key] (keeps out when absent) whose components obey `rule`; sources
// may be NULL.
static bool read_vector(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                        number_rule rule, double out[3], int32_t sources[3])
{
	if (sources != NULL)
		sources[0] = sources[1] = sources[2] = -1;
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	child_key(sub, path, key);
	if (!json_is_array(value) || json_array_size(value) != 3)
		return fail(p, SM_ERROR_SCHEMA, sub, "must be an array of 3 numbers [x, y, z], not %s%s",
		            type_name(value), json_is_array(value) ? " of another length" : "");
	for (size_t c = 0; c < 3; c++) {
		char element[PATH_CAPACITY];
		child_index(element, sub, c);
		int32_t source;
		double v = 0.0;
		if (!read_number(p, use, key_unit(p, key), json_array_get(value, c), element, &v, &source) ||
		    !check_rule(p, element, v, source, rule))
			return false;
		out[c] = v;
		if (sources != NULL)
			sources[c] = source;
	}
	return true;
}

static bool read_bool(parser* p, const json_t* obj, const char* path, const char* key, bool* out)
{
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	child_key(sub, path, key);
	if (!json_is_boolean(value))
		return fail(p, SM_ERROR_SCHEMA, sub, "must be true or false, not %s", type_name(value));
	*out = json_is_true(value);
	return true;
}

// A name: a non-empty string without control characters or line breaks, at most
// MAX_NAME_BYTES long; `identifier` also asks for a C identifier (letters, digits, '_', not
// starting with a digit).
static bool check_name_text(parser* p, const char* s, size_t n, const char* path, bool identifier)
{
	if (n == 0 || n > MAX_NAME_BYTES)
		return fail(p, SM_ERROR_SCHEMA, path, "a name must have 1 to %d bytes (this one has %zu)",
		            MAX_NAME_BYTES, n);
	char text[TEXT_QUOTED_CAPACITY];
	int64_t position;
	const int32_t c = sm_text_find_refused(s, sm_text_refused_in_name, &position);
	if (c >= 0)
		return fail(p, SM_ERROR_SCHEMA, path, "name %s has %s, U+%04X, at character %lld",
		            sm_text_quoted(text, s),
		            sm_text_is_line_break(c) ? "a line break" : "a control character", (unsigned)c,
		            (long long)position);
	for (size_t i = 0; i < n && identifier; i++) {
		const unsigned char b = (unsigned char)s[i];
		const bool letter = (b >= 'a' && b <= 'z') || (b >= 'A' && b <= 'Z') || b == '_';
		const bool digit = b >= '0' && b <= '9';
		if (!(letter || (digit && i > 0)))
			return fail(p, SM_ERROR_SCHEMA, path,
			            "name %s must be an identifier (letters, digits and '_', not starting with a digit)",
			            sm_text_quoted(text, s));
	}
	return true;
}

static bool check_name(parser* p, const json_t* value, const char* path, bool identifier, const char** out)
{
	if (!json_is_string(value))
		return fail(p, SM_ERROR_SCHEMA, path, "must be a string, not %s", type_name(value));
	if (!check_name_text(p, json_string_value(value), json_string_length(value), path, identifier))
		return false;
	*out = json_string_value(value);
	return true;
}

// ---------------------------------------------------------------------------------------------
// Expansion storage: per-particle and per-spring sources, particle names.
// ---------------------------------------------------------------------------------------------

static void expansion_free(expansion* ex)
{
	if (ex == NULL)
		return;
	sm_model_destroy(ex->model);
	free(ex->particle_sources);
	free(ex->spring_sources);
	free(ex->name_offset);
	free(ex->names);
	sm_name_index_free(&ex->particle_names);
	free(ex->structures);
	sm_name_index_free(&ex->structure_names);
	free(ex->loads);
	free(ex->ports);
	sm_name_index_free(&ex->port_names);
	free(ex->parameter_uses);
	free(ex->parameter_units);
	free(ex);
}

// Room for `needed` elements of `size` bytes in `array` of *capacity elements, the capacity doubled
// from 16 as needed: *grown is the array to keep (array itself when it has room), or false, with
// both as they were, when memory runs out.
static bool grow_array(void* array, int64_t* capacity, int64_t needed, size_t size, void** grown)
{
	*grown = array;
	if (needed <= *capacity)
		return true;
	int64_t c = *capacity > 0 ? *capacity : 16;
	while (c < needed)
		c *= 2;
	void* q = realloc(array, (size_t)c * size);
	if (q == NULL)
		return false;
	*grown = q;
	*capacity = c;
	return true;
}

// grow_array on `array`, a pointer of any type, assigned as its own type (written through a void**
// it would break C's aliasing rules) by way of the caller's void* `spare`.
#define GROW_ARRAY(array, capacity, needed, spare)                                                           \
	(grow_array((array), (capacity), (needed), sizeof *(array), &(spare)) && ((array) = (spare), true))

// Room for the sources and names of `particles` and `springs` in all.
static bool reserve(parser* p, int64_t particles, int64_t springs)
{
	expansion* ex = p->ex;
	int64_t pc = ex->particle_capacity;
	void* spare;
	if (!GROW_ARRAY(ex->particle_sources, &pc, particles, spare))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld particles", (long long)particles);
	pc = ex->particle_capacity;
	if (!GROW_ARRAY(ex->name_offset, &pc, particles, spare))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld particles", (long long)particles);
	ex->particle_capacity = pc;
	if (!GROW_ARRAY(ex->spring_sources, &ex->spring_capacity, springs, spare))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld springs", (long long)springs);
	return true;
}

// The names of the expansion's particles, structures and ports, and of the document's
// parameters, for their name indexes.
static const char* particle_name(const void* owner, int32_t particle)
{
	const expansion* ex = owner;
	return ex->names + ex->name_offset[particle];
}

// "particle 10 (\"rope[10]\")", or "particle 10" for an unnamed one, for messages.
static const char* describe_particle(const expansion* ex, int32_t particle, char* buffer, size_t size)
{
	char text[TEXT_QUOTED_CAPACITY];
	if (ex->name_offset[particle] >= 0)
		snprintf(buffer, size, "particle %d (%s)", (int)particle,
		         sm_text_quoted(text, particle_name(ex, particle)));
	else
		snprintf(buffer, size, "particle %d", (int)particle);
	return buffer;
}

static const char* structure_name(const void* owner, int32_t structure)
{
	return ((const expansion*)owner)->structures[structure].name;
}

static const char* port_name(const void* owner, int32_t port)
{
	return ((const expansion*)owner)->ports[port].name;
}

static const char* parameter_name(const void* owner, int32_t parameter)
{
	return ((const sm_document*)owner)->parameter_names[parameter];
}

static int32_t lookup_name(const expansion* ex, const char* name)
{
	return sm_name_index_find(&ex->particle_names, name, strlen(name));
}

// Gives particle `index` the name (formatted); fails if the name is taken.
static bool name_particle(parser* p, const char* path, int32_t index, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static bool name_particle(parser* p, const char* path, int32_t index, const char* format, ...)
{
	expansion* ex = p->ex;
	char name[MAX_NAME_BYTES + 1];
	va_list args;
	va_start(args, format);
	const int written = vsnprintf(name, sizeof name, format, args);
	va_end(args);
	// Only a limit on elements above SM_DOCUMENT_MAX_ELEMENTS (sm_document_parse_limited) can
	// make a structure's particle names longer than MAX_STRUCTURE_NAME_BYTES allows for.
	char text[TEXT_QUOTED_CAPACITY];
	if (written < 0 || written > MAX_NAME_BYTES)
		return fail(p, SM_ERROR_SCHEMA, path, "particle name %s would have more than %d bytes",
		            sm_text_quoted(text, name), MAX_NAME_BYTES);
	const int32_t other = lookup_name(ex, name);
	if (other >= 0)
		return fail(p, SM_ERROR_SCHEMA, path, "particle name %s is already used by particle %d",
		            sm_text_quoted(text, name), (int)other);
	const int64_t length = (int64_t)strlen(name) + 1;
	void* spare;
	if (!GROW_ARRAY(ex->names, &ex->names_capacity, ex->names_length + length, spare))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for particle names");
	memcpy(ex->names + ex->names_length, name, (size_t)length);
	ex->name_offset[index] = ex->names_length;
	int32_t holder;
	if (!sm_name_index_insert(&ex->particle_names, name, (size_t)length - 1, index, &holder)) {
		ex->name_offset[index] = -1;
		return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for particle names");
	}
	ex->names_length += length;
	return true;
}

static const document_structure* find_structure(const expansion* ex, const char* name, size_t length)
{
	const int32_t s = sm_name_index_find(&ex->structure_names, name, length);
	return s >= 0 ? &ex->structures[s] : NULL;
}

// The parameters named in the indices of one structure reference.
typedef struct index_parameters {
	parser* p;
	noted_parameters noted;
} index_parameters;

// A parameter named in an index of a structure reference (index_expression_lookup_fn).
static bool lookup_index_parameter(void* context, const char* name, size_t length, double* value)
{
	index_parameters* named = context;
	parser* p = named->p;
	const int32_t k = sm_name_index_find(&p->doc->parameter_index, name, length);
	if (k < 0)
		return false;
	*value = p->parameter_values[k];
	p->ex->parameter_uses[k] |= (uint8_t)FEEDS_REFERENCES;
	note_unit(p->ex, k, NULL);
	note_parameter(&named->noted, k);
	return true;
}

// The particle of structure s that "name[...]" names (text: the reference quoted for messages;
// open: its '['): one to three indices, each a whole number or an expression of parameters
// (index_expression.h). One index is the particle's position in the structure; two are row and
// column of a sheet; three row, column and layer of a block. A message on a value names the
// parameters the indices came from, and only those; on success they join the element's noted
// parameters, for its later messages.
static bool resolve_structure_reference(parser* p, const document_structure* s, const char* open,
                                        const char* text, const char* path, int32_t* out)
{
	static const char* const form =
	    "a structure reference is name[i], name[row, column] or name[row, column, layer]";
	index_parameters named = {p, {{0}, 0, false}};
	int64_t c[3];
	int count = 0;
	const char* q = open + 1;
	for (;;) {
		char why[INDEX_EXPRESSION_MESSAGE_CAPACITY];
		char message[SM_ERROR_MESSAGE_CAPACITY];
		const char* end;
		const index_expression_status status =
		    count < 3 ? sm_index_expression_evaluate(q, lookup_index_parameter, &named, &c[count], &end, why)
			          : INDEX_EXPRESSION_SYNTAX;
		if (status == INDEX_EXPRESSION_UNKNOWN_NAME)
			return fail(p, SM_ERROR_NOT_FOUND, path, "%s: %s", text, why);
		if (status == INDEX_EXPRESSION_NOT_WHOLE)
			return fail(p, SM_ERROR_SCHEMA, path, "%s: %s", text, why);
		if (status == INDEX_EXPRESSION_INVALID) {
			snprintf(message, sizeof message, "%s: %s", text, why);
			return fail_naming(p, SM_ERROR_SCHEMA, path, message, &named.noted);
		}
		if (status == INDEX_EXPRESSION_SYNTAX && count < 3)
			return fail(p, SM_ERROR_SCHEMA, path, "%s: %s; %s", text, why, form);
		if (status != INDEX_EXPRESSION_OK || (*end == ']' && end[1] != '\0') || *end == '\0')
			return fail(p, SM_ERROR_SCHEMA, path, "%s: %s", text, form);
		count++;
		if (*end == ']')
			break;
		q = end + 1;  // past the ','
	}
	// One index for any structure; two (row, column) for a sheet, three for a block.
	const int grid_indices = s->type == STRUCTURE_SHEET ? 2 : s->type == STRUCTURE_BLOCK ? 3 : 1;
	if (count != 1 && count != grid_indices) {
		static const char* const forms[] = {
		    "a rope takes one index, name[i]", "a sheet takes name[i] or name[row, column]",
		    "a block takes name[i] or name[row, column, layer]", "a mesh takes one index, name[i]"};
		return fail(p, SM_ERROR_PARTICLE_INDEX, path, "%s has %d indices: %s", text, count, forms[s->type]);
	}
	const sm_structure* r = &s->range;
	int64_t index = -1;
	if (count == 1 && c[0] >= 0 && c[0] < r->particle_count)
		index = r->first_particle + c[0];
	else if (count == 2 && r->shape[2] == 1 && c[0] >= 0 && c[1] >= 0 && c[0] < r->shape[1] &&
	         c[1] < r->shape[0])
		index = sm_structure_particle(r, (int32_t)c[0], (int32_t)c[1], 0);
	else if (count == 3 && c[0] >= 0 && c[1] >= 0 && c[2] >= 0 && c[0] < r->shape[1] && c[1] < r->shape[0] &&
	         c[2] < r->shape[2])
		index = sm_structure_particle(r, (int32_t)c[0], (int32_t)c[1], (int32_t)c[2]);
	if (index >= 0) {
		*out = (int32_t)index;
		for (int k = 0; k < named.noted.count; k++)
			note_parameter(&p->noted, named.noted.index[k]);
		p->noted.more = p->noted.more || named.noted.more;
		return true;
	}
	char message[SM_ERROR_MESSAGE_CAPACITY];
	if (s->type == STRUCTURE_SHEET)
		snprintf(message, sizeof message,
		         "%s is outside structure %s (rows 0 to %d, columns 0 to %d, or [0] to [%d])", text, s->name,
		         (int)r->shape[1] - 1, (int)r->shape[0] - 1, (int)r->particle_count - 1);
	else if (s->type == STRUCTURE_BLOCK)
		snprintf(message, sizeof message,
		         "%s is outside structure %s (rows 0 to %d, columns 0 to %d, layers 0 to %d, or [0] to [%d])",
		         text, s->name, (int)r->shape[1] - 1, (int)r->shape[0] - 1, (int)r->shape[2] - 1,
		         (int)r->particle_count - 1);
	else
		snprintf(message, sizeof message, "%s is outside structure %s ([0] to [%d])", text, s->name,
		         (int)r->particle_count - 1);
	return fail_naming(p, SM_ERROR_PARTICLE_INDEX, path, message, &named.noted);
}

// A particle reference: an index, a particle's name, or "structure[i, j, k]"
// (resolve_structure_reference).
static bool resolve_particle(parser* p, const json_t* value, const char* path, int32_t* out)
{
	const int32_t n = sm_model_particle_count(p->ex->model);
	if (json_is_integer(value)) {
		const json_int_t i = json_integer_value(value);
		if (i < 0 || i >= n)
			return fail(p, SM_ERROR_PARTICLE_INDEX, path,
			            "particle index %lld is out of range (the model has %d particle%s)", (long long)i,
			            (int)n, n == 1 ? "" : "s");
		*out = (int32_t)i;
		return true;
	}
	if (json_is_real(value)) {
		// 3.0 is index 3, as a count may be written 3.0; 2.5 is no index.
		const double v = json_real_value(value);
		char text[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(v, text);
		if (!(v == floor(v)))
			return fail(p, SM_ERROR_SCHEMA, path, "a particle index must be a whole number, not %s", text);
		if (!(v >= 0.0 && v < (double)n))
			return fail(p, SM_ERROR_PARTICLE_INDEX, path,
			            "particle index %s is out of range (the model has %d particle%s)", text, (int)n,
			            n == 1 ? "" : "s");
		*out = (int32_t)v;
		return true;
	}
	if (!json_is_string(value))
		return fail(p, SM_ERROR_SCHEMA, path, "must be a particle name or index, not %s", type_name(value));
	const char* name = json_string_value(value);
	char text[TEXT_QUOTED_CAPACITY];
	sm_text_quoted(text, name);
	const int32_t found = lookup_name(p->ex, name);
	if (found >= 0) {
		*out = found;
		return true;
	}
	// "structure[...]": indices with other spacing than the generated names, or expressions.
	const char* open = strchr(name, '[');
	const size_t length = strlen(name);
	if (open != NULL && length > 0 && name[length - 1] == ']') {
		const document_structure* s = find_structure(p->ex, name, (size_t)(open - name));
		if (s != NULL)
			return resolve_structure_reference(p, s, open, text, path, out);
	}
	// A parameter's name is no particle reference: an index is written as a number, and only a
	// structure reference's indices take parameters.
	if (find_parameter(p->doc, name) >= 0)
		return fail(p, SM_ERROR_NOT_FOUND, path,
		            "no particle named %s (%s is a parameter, and a parameter cannot stand for a particle's "
		            "index: name the particle, or refer to a structure's particle as name[i] with i an "
		            "expression of parameters)",
		            text, text);
	return fail(p, SM_ERROR_NOT_FOUND, path, "no particle named %s", text);
}

// ---------------------------------------------------------------------------------------------
// Particles.
// ---------------------------------------------------------------------------------------------

static bool read_particles(parser* p, const json_t* list)
{
	static const char* const keys[] = {"name", "position", "velocity", "mass", "fixed", NULL};
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "particles", "must be an array of particles, not %s",
		            type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return fail(p, SM_ERROR_SCHEMA, "particles", "%zu particles exceed the limit of %lld", n,
		            (long long)p->doc->max_elements);
	if (!reserve(p, (int64_t)n, 0))
		return false;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY];
		child_index(path, "particles", k);
		const json_t* obj = json_array_get(list, k);
		if (!expect_object(p, obj, path) || !check_keys(p, obj, path, keys))
			return false;
		sm_particle_def def = sm_default_particle_def();
		particle_source src;
		bool fixed = false;
		if (!require(p, obj, path, "position") ||
		    !read_vector(p, FEEDS_STATE, obj, path, "position", ANY_FINITE, def.position, src.position) ||
		    !read_vector(p, FEEDS_STATE, obj, path, "velocity", ANY_FINITE, def.velocity, src.velocity) ||
		    !read_field(p, FEEDS_CONSTANTS, obj, path, "mass", MASS, &def.mass, &src.mass) ||
		    !read_bool(p, obj, path, "fixed", &fixed))
			return false;
		def.motion = fixed ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
		int32_t index;
		if (sm_model_add_particle(p->ex->model, &def, &index) != SM_OK)
			return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "%s", sm_model_last_error(p->ex->model));
		p->ex->particle_sources[index] = src;
		p->ex->name_offset[index] = -1;
		const json_t* name = json_object_get(obj, "name");
		if (name != NULL) {
			char sub[PATH_CAPACITY];
			child_key(sub, path, "name");
			const char* s;
			if (!check_name(p, name, sub, false, &s) || !name_particle(p, sub, index, "%s", s))
				return false;
		}
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Springs.
// ---------------------------------------------------------------------------------------------

// The key of a constant ("stiffness" or "damping") given with a scaling: "stiffness",
// "strain_stiffness" or "section_stiffness".
static const char* constant_key(const char* constant, sm_scaling scaling)
{
	static const char* const keys[2][3] = {{"stiffness", "strain_stiffness", "section_stiffness"},
	                                       {"damping", "strain_damping", "section_damping"}};
	return keys[strcmp(constant, "damping") == 0][scaling];
}

// Which of a constant's keys obj gives (at most one): its scaling, SM_ABSOLUTE when none.
static bool read_scaling(parser* p, const json_t* obj, const char* path, const char* constant,
                         sm_scaling* scaling)
{
	static const sm_scaling scalings[3] = {SM_ABSOLUTE, SM_PER_STRAIN, SM_PER_SECTION};
	int given = 0;
	*scaling = SM_ABSOLUTE;
	for (int k = 0; k < 3; k++)
		if (json_object_get(obj, constant_key(constant, scalings[k])) != NULL) {
			given++;
			*scaling = scalings[k];
		}
	if (given > 1)
		return fail(p, SM_ERROR_SCHEMA, path, "give one of \"%s\", \"%s\" and \"%s\", not more",
		            constant_key(constant, SM_ABSOLUTE), constant_key(constant, SM_PER_STRAIN),
		            constant_key(constant, SM_PER_SECTION));
	return true;
}

// Stiffness and damping, each absolute ("stiffness" [N/m], "damping" [N s/m]), per unit strain
// ("strain_stiffness" [N], "strain_damping" [N s]) or per unit strain and section
// ("section_stiffness", "section_damping": sm_scaling's SM_PER_SECTION), and "break_strain".
static bool read_constants(parser* p, const json_t* obj, const char* path, sm_spring_material* m,
                           spring_source* src)
{
	if (!read_scaling(p, obj, path, "stiffness", &m->stiffness_scaling) ||
	    !read_scaling(p, obj, path, "damping", &m->damping_scaling))
		return false;
	m->stiffness = 0.0;
	m->damping = 0.0;
	m->break_strain = INFINITY;
	if (!read_field(p, FEEDS_CONSTANTS, obj, path, constant_key("stiffness", m->stiffness_scaling),
	                NON_NEGATIVE, &m->stiffness, &src->stiffness) ||
	    !read_field(p, FEEDS_CONSTANTS, obj, path, constant_key("damping", m->damping_scaling), NON_NEGATIVE,
	                &m->damping, &src->damping))
		return false;
	const json_t* brk = json_object_get(obj, "break_strain");
	src->break_strain = -1;
	if (brk != NULL && !read_field(p, FEEDS_CONSTANTS, obj, path, "break_strain", POSITIVE, &m->break_strain,
	                               &src->break_strain))
		return false;
	return true;
}

static bool read_springs(parser* p, const json_t* list)
{
	static const char* const keys[] = {"a",
	                                   "b",
	                                   "kind",
	                                   "rest_length",
	                                   "stiffness",
	                                   "strain_stiffness",
	                                   "section_stiffness",
	                                   "damping",
	                                   "strain_damping",
	                                   "section_damping",
	                                   "section",
	                                   "break_strain",
	                                   NULL};
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "springs", "must be an array of springs, not %s", type_name(list));
	const size_t n = json_array_size(list);
	sm_model* model = p->ex->model;
	if ((int64_t)n + sm_model_spring_count(model) > p->doc->max_elements)
		return fail(p, SM_ERROR_SCHEMA, "springs", "%zu more springs exceed the limit of %lld", n,
		            (long long)p->doc->max_elements);
	if (!reserve(p, sm_model_particle_count(model), sm_model_spring_count(model) + (int64_t)n))
		return false;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		child_index(path, "springs", k);
		const json_t* obj = json_array_get(list, k);
		if (!expect_object(p, obj, path) || !check_keys(p, obj, path, keys) || !require(p, obj, path, "a") ||
		    !require(p, obj, path, "b"))
			return false;
		sm_spring_def def = sm_default_spring_def();
		forget_parameters(p);
		child_key(sub, path, "a");
		if (!resolve_particle(p, json_object_get(obj, "a"), sub, &def.a))
			return false;
		child_key(sub, path, "b");
		if (!resolve_particle(p, json_object_get(obj, "b"), sub, &def.b))
			return false;
		if (def.a == def.b) {
			char message[SM_ERROR_MESSAGE_CAPACITY];
			char which[TEXT_QUOTED_CAPACITY + 32];
			snprintf(message, sizeof message, "connects %s to itself (a and b are the same particle)",
			         describe_particle(p->ex, def.a, which, sizeof which));
			return fail_naming_parameters(p, SM_ERROR_SELF_SPRING, path, message);
		}
		spring_source src = {-1, -1, -1, -1, -1, false};
		sm_spring_material m;
		if (!read_constants(p, obj, path, &m, &src))
			return false;
		// A spring's own section: per-section constants of a single spring need it.
		const bool per_section = m.stiffness_scaling == SM_PER_SECTION || m.damping_scaling == SM_PER_SECTION;
		if (json_object_get(obj, "section") != NULL) {
			if (!per_section)
				return fail(p, SM_ERROR_SCHEMA, path,
				            "\"section\" goes with \"section_stiffness\" or \"section_damping\"");
			if (!read_field(p, FEEDS_CONSTANTS, obj, path, "section", POSITIVE, &def.section, &src.section))
				return false;
		} else if (per_section) {
			return fail(
			    p, SM_ERROR_SCHEMA, path,
			    "per-section constants need the spring's \"section\" (the width [m] or area [m^2] it stands "
			    "for)");
		}
		def.stiffness = m.stiffness;
		def.stiffness_scaling = m.stiffness_scaling;
		def.damping = m.damping;
		def.damping_scaling = m.damping_scaling;
		def.break_strain = m.break_strain;
		// "kind" defaults to zero-length for "rest_length": 0 and rest-length otherwise, so that
		// without a kind the rest length also chooses the spring's law.
		const json_t* rest = json_object_get(obj, "rest_length");
		const json_t* kind = json_object_get(obj, "kind");
		const feeds rest_use = kind != NULL ? FEEDS_CONSTANTS : FEEDS_CONSTANTS | FEEDS_SPRING_KINDS;
		src.kind_given = kind != NULL;
		if (rest != NULL && !read_field(p, rest_use, obj, path, "rest_length", NON_NEGATIVE, &def.rest_length,
		                                &src.rest_length))
			return false;
		def.kind = rest != NULL && def.rest_length == 0.0 ? SM_SPRING_ZERO_LENGTH : SM_SPRING_REST_LENGTH;
		if (kind != NULL) {
			child_key(sub, path, "kind");
			const char* s = json_is_string(kind) ? json_string_value(kind) : "";
			if (strcmp(s, "zero_length") == 0)
				def.kind = SM_SPRING_ZERO_LENGTH;
			else if (strcmp(s, "rest_length") == 0)
				def.kind = SM_SPRING_REST_LENGTH;
			else
				return fail(p, SM_ERROR_SCHEMA, sub, "must be \"rest_length\" or \"zero_length\"");
			char text[DESCRIPTION_CAPACITY];
			if (def.kind == SM_SPRING_ZERO_LENGTH && rest != NULL && def.rest_length != 0.0)
				return fail(p, SM_ERROR_SCHEMA, path, "a zero-length spring cannot have rest_length %s",
				            describe(p, text, sizeof text, def.rest_length, src.rest_length));
		}
		if (def.kind == SM_SPRING_ZERO_LENGTH)
			def.rest_length = 0.0;
		int32_t index;
		const sm_status st = sm_model_add_spring(model, &def, &index);
		if (st != SM_OK) {
			// The model numbers springs from structures first; the path already names this one.
			const char* message = sm_model_last_error(model);
			const char* rule = strncmp(message, "spring ", 7) == 0 ? strstr(message, ": ") : NULL;
			return fail_naming_parameters(p, st, path, rule != NULL ? rule + 2 : message);
		}
		p->ex->spring_sources[index] = src;
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Structures.
// ---------------------------------------------------------------------------------------------

// A group of springs; absent means no springs of that group, and so do literal zero constants.
// A group whose stiffness or damping is a parameter is created whatever values they take, so
// that changing parameters never changes the model's topology (an FMU's tunable parameters).
static bool read_material(parser* p, const json_t* obj, const char* path, const char* key,
                          sm_spring_material* m, spring_source* src)
{
	static const char* const keys[] = {"stiffness",      "strain_stiffness", "section_stiffness", "damping",
	                                   "strain_damping", "section_damping",  "break_strain",      NULL};
	*m = sm_default_spring_material();
	*src = (spring_source){-1, -1, -1, -1, -1, false};
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	child_key(sub, path, key);
	if (!expect_object(p, value, sub) || !check_keys(p, value, sub, keys))
		return false;
	// A group that gives neither constant makes no springs: a forgotten stiffness, not a choice
	// (zeros given make none too, as asked).
	bool constants = false;
	for (const char* const* k = keys; *k != NULL; k++)
		constants = constants || (strcmp(*k, "break_strain") != 0 && json_object_get(value, *k) != NULL);
	if (!constants)
		return fail(p, SM_ERROR_SCHEMA, sub,
		            "gives no stiffness and no damping, so it would make no springs (give stiffness, "
		            "strain_stiffness or section_stiffness, or a damping; or leave the group out)");
	if (!read_constants(p, value, sub, m, src))
		return false;
	m->keep_when_zero = src->stiffness >= 0 || src->damping >= 0;
	return true;
}

// Fails if `particles` and `springs` more would take the model past the document's limit;
// otherwise makes room for their sources.
static bool check_budget(parser* p, const char* path, int64_t particles, int64_t springs)
{
	const sm_model* model = p->ex->model;
	const int64_t np = sm_model_particle_count(model) + particles,
	              ns = sm_model_spring_count(model) + springs;
	const long long limit = p->doc->max_elements;
	if (np > limit && ns > limit)
		return fail(
		    p, SM_ERROR_SCHEMA, path,
		    "the model would have %lld particles and %lld springs, more than the limit of %lld of each",
		    (long long)np, (long long)ns, limit);
	if (np > limit || ns > limit)
		return fail(p, SM_ERROR_SCHEMA, path, "the model would have %lld %s, more than the limit of %lld",
		            (long long)(np > limit ? np : ns), np > limit ? "particles" : "springs", limit);
	return reserve(p, np, ns);
}

// Mesh vertices [[x, y, z], ...] and triangles [[a, b, c], ...], copied into arrays.
static bool read_mesh_arrays(parser* p, const json_t* obj, const char* path, double** vertices,
                             int32_t* vertex_count, int32_t** triangles, int32_t* triangle_count)
{
	char sub[PATH_CAPACITY];
	const json_t* vs = json_object_get(obj, "vertices");
	const json_t* ts = json_object_get(obj, "triangles");
	child_key(sub, path, "vertices");
	if (!json_is_array(vs))
		return fail(p, SM_ERROR_SCHEMA, sub, "must be an array of [x, y, z] vertices, not %s", type_name(vs));
	child_key(sub, path, "triangles");
	if (!json_is_array(ts))
		return fail(p, SM_ERROR_SCHEMA, sub, "must be an array of [a, b, c] vertex index triples, not %s",
		            type_name(ts));
	// The springs are counted once the mesh is built (its edges are known then).
	const size_t nv = json_array_size(vs), nt = json_array_size(ts);
	if (!check_budget(p, path, (int64_t)nv, 0))
		return false;
	*vertices = malloc((nv > 0 ? nv : 1) * 3 * sizeof(double));
	*triangles = malloc((nt > 0 ? nt : 1) * 3 * sizeof(int32_t));
	if (*vertices == NULL || *triangles == NULL)
		return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for %zu vertices", nv);
	for (size_t v = 0; v < nv; v++) {
		char element[PATH_CAPACITY];
		snprintf(element, sizeof element, "%.100s.vertices[%zu]", path, v);
		const json_t* vector = json_array_get(vs, v);
		if (!json_is_array(vector) || json_array_size(vector) != 3)
			return fail(p, SM_ERROR_SCHEMA, element, "must be an array of 3 numbers [x, y, z], not %s%s",
			            type_name(vector), json_is_array(vector) ? " of another length" : "");
		for (size_t c = 0; c < 3; c++) {
			char coordinate[PATH_CAPACITY];
			child_index(coordinate, element, c);
			double x = 0.0;
			int32_t source;
			if (!read_number(p, FEEDS_STATE, "m", json_array_get(vector, c), coordinate, &x, &source) ||
			    !check_rule(p, coordinate, x, source, ANY_FINITE))
				return false;
			(*vertices)[3 * v + c] = x;
		}
	}
	for (size_t t = 0; t < nt; t++) {
		char element[PATH_CAPACITY];
		snprintf(element, sizeof element, "%.100s.triangles[%zu]", path, t);
		const json_t* triple = json_array_get(ts, t);
		if (json_is_array(triple) && json_array_size(triple) != 3)
			return fail(p, SM_ERROR_SCHEMA, element, "must be an array of 3 vertex indices, not of %zu",
			            json_array_size(triple));
		if (!json_is_array(triple))
			return fail(p, SM_ERROR_SCHEMA, element, "must be an array of 3 vertex indices, not %s",
			            type_name(triple));
		for (size_t c = 0; c < 3; c++) {
			char corner[PATH_CAPACITY];
			child_index(corner, element, c);
			int64_t index;
			if (!read_count(p, FEEDS_COUNTS, json_array_get(triple, c), corner, 0,
			                nv > 0 ? (int64_t)nv - 1 : 0, &index))
				return false;
			(*triangles)[3 * t + c] = (int32_t)index;
		}
	}
	*vertex_count = (int32_t)nv;
	*triangle_count = (int32_t)nt;
	return true;
}

// Notes the parameters that gave the vertex indices of the first triangle that repeats a vertex,
// the one sm_add_mesh refuses (count triangles of 3 indices each, read from obj's "triangles").
static void note_repeating_triangle(const parser* p, const json_t* obj, const int32_t* triangles,
                                    int32_t count, noted_parameters* noted)
{
	const json_t* list = json_object_get(obj, "triangles");
	for (int32_t t = 0; t < count; t++) {
		const int32_t* tri = triangles + 3 * (size_t)t;
		if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2])
			continue;
		for (size_t c = 0; c < 3; c++) {
			const char* name = json_string_value(json_array_get(json_array_get(list, (size_t)t), c));
			const int32_t k = name != NULL ? find_parameter(p->doc, name) : -1;
			if (k >= 0)
				note_parameter(noted, k);
		}
		return;
	}
}

// Group of spring s of a structure, from the offset between its particles (see structures.h).
static int spring_group(const document_structure* s, const sm_model* model, int32_t spring)
{
	sm_spring_def def;
	sm_model_get_spring(model, spring, &def);
	const sm_structure* r = &s->range;
	const int32_t a = def.a - r->first_particle, b = def.b - r->first_particle;
	switch (s->type) {
	case STRUCTURE_ROPE: return b - a == 1 ? 0 : 1;
	case STRUCTURE_SHEET: {
		const int32_t nu = r->shape[0];
		const int32_t di = b / nu - a / nu;
		const int32_t dj = b % nu - a % nu;
		if ((di == 0 && dj == 1) || (di == 1 && dj == 0))
			return 0;
		return di == 1 ? 1 : 2;
	}
	case STRUCTURE_BLOCK: {
		const int32_t nu = r->shape[0], nv = r->shape[1];
		const int32_t dk = b / (nu * nv) - a / (nu * nv);
		const int32_t di = (b / nu) % nv - (a / nu) % nv;
		const int32_t dj = b % nu - a % nu;
		const int nonzero = (di != 0) + (dj != 0) + (dk != 0);
		return nonzero - 1;
	}
	case STRUCTURE_MESH: return spring - r->first_spring < r->group_spring_count[0] ? 0 : 1;
	}
	return 0;
}

// Springs of a rope of nu particles (nv = nw = 1), a sheet of nu x nv or a block of nu x nv x nw
// in the groups present, as their builders make them (structures.h): a rope joins particle p
// to p + 1 (structural) and p + 2 (bending); a sheet joins (i, j) to (i, j + 1) and (i + 1, j)
// (structural), to (i + 1, j + 1) and (i + 1, j - 1) (shear), to (i, j + 2) and (i + 2, j)
// (bend); a block joins neighbours along each axis (edge), across both diagonals of every
// lattice face (face_diagonal) and along the four diagonals of every cell (body_diagonal).
static int64_t grid_springs(structure_type type, int64_t nu, int64_t nv, int64_t nw, const bool present[3])
{
	int64_t group[3] = {0, 0, 0};
	if (type == STRUCTURE_ROPE) {
		group[0] = nu - 1;
		group[1] = nu - 2;
	} else if (type == STRUCTURE_SHEET) {
		group[0] = (nu - 1) * nv + nu * (nv - 1);
		group[1] = 2 * (nu - 1) * (nv - 1);
		group[2] = (nu - 2) * nv + nu * (nv - 2);
	} else if (type == STRUCTURE_BLOCK) {
		group[0] = (nu - 1) * nv * nw + nu * (nv - 1) * nw + nu * nv * (nw - 1);
		group[1] = 2 * ((nu - 1) * (nv - 1) * nw + (nu - 1) * nv * (nw - 1) + nu * (nv - 1) * (nw - 1));
		group[2] = 4 * (nu - 1) * (nv - 1) * (nw - 1);
	}
	return (present[0] ? group[0] : 0) + (present[1] ? group[1] : 0) + (present[2] ? group[2] : 0);
}

// A rope's, sheet's or block's "mass_distribution": "even" (the default) or "lumped".
static bool read_distribution(parser* p, const json_t* obj, const char* path,
                              sm_mass_distribution* distribution)
{
	const json_t* value = json_object_get(obj, "mass_distribution");
	if (value == NULL)
		return true;
	const char* text = json_is_string(value) ? json_string_value(value) : "";
	if (strcmp(text, "even") == 0)
		*distribution = SM_MASS_EVEN;
	else if (strcmp(text, "lumped") == 0)
		*distribution = SM_MASS_LUMPED;
	else {
		char sub[PATH_CAPACITY];
		child_key(sub, path, "mass_distribution");
		return fail(p, SM_ERROR_SCHEMA, sub, "must be \"even\" or \"lumped\"");
	}
	return true;
}

// The particles of "particles" whose names read as references to a structure S, "S[...]", by S
// (the first of them for each S), so that each structure's name is looked up among them rather
// than searched for in every particle's name.
typedef struct named_like_references {
	name_index index;   // S -> entry
	char* prefixes;     // every entry's S, NUL-terminated, one after the other
	int64_t* offset;    // entry -> its S in prefixes
	int32_t* particle;  // entry -> the particle's place in "particles"
} named_like_references;

static const char* named_like_prefix(const void* owner, int32_t entry)
{
	const named_like_references* like = owner;
	return like->prefixes + like->offset[entry];
}

static void named_like_free(named_like_references* like)
{
	sm_name_index_free(&like->index);
	free(like->prefixes);
	free(like->offset);
	free(like->particle);
}

// Fills *like (sm_name_index_init'ed with it as owner) from the particles read before.
static bool find_names_like_references(parser* p, named_like_references* like)
{
	const json_t* list = json_object_get(p->doc->root, "particles");
	const size_t n = json_array_size(list);
	size_t bytes = 0;
	for (size_t k = 0; k < n; k++) {
		const char* name = json_string_value(json_object_get(json_array_get(list, k), "name"));
		bytes += name != NULL ? strlen(name) + 1 : 0;
	}
	like->prefixes = malloc(bytes + 1);
	like->offset = malloc((n + 1) * sizeof(int64_t));
	like->particle = malloc((n + 1) * sizeof(int32_t));
	if (like->prefixes == NULL || like->offset == NULL || like->particle == NULL)
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "particles", "out of memory");
	int64_t used = 0;
	int32_t entries = 0;
	for (size_t k = 0; k < n; k++) {
		// S is what comes before the first '[' (a structure's name holds none), of a name that
		// ends with ']' after it.
		const char* name = json_string_value(json_object_get(json_array_get(list, k), "name"));
		const char* open = name != NULL ? strchr(name, '[') : NULL;
		const size_t length = open != NULL ? (size_t)(open - name) : 0;
		const size_t name_bytes = name != NULL ? strlen(name) : 0;
		if (open == NULL || length == 0 || name_bytes <= length + 1 || name[name_bytes - 1] != ']')
			continue;
		memcpy(like->prefixes + used, name, length);
		like->prefixes[used + (int64_t)length] = '\0';
		like->offset[entries] = used;
		like->particle[entries] = (int32_t)k;
		int32_t holder;
		if (!sm_name_index_insert(&like->index, name, length, entries, &holder))
			return fail(p, SM_ERROR_OUT_OF_MEMORY, "particles", "out of memory");
		if (holder < 0) {
			used += (int64_t)length + 1;
			entries++;
		}
	}
	return true;
}

// A particle's own name may not read as a reference to structure `structure` (its name, `length`
// bytes): "cloth[2]" beside a structure "cloth" would take over the reference to cloth's particle
// 2 (names are looked up first), and "cloth[0, 2]" would stand beside the generated "cloth[0,2]".
// Checked when the structure is read, before its particles are named (the particles come first).
static bool check_names_against_structure(parser* p, const named_like_references* like, const char* structure,
                                          size_t length)
{
	const int32_t entry = sm_name_index_find(&like->index, structure, length);
	if (entry < 0)
		return true;
	const size_t k = (size_t)like->particle[entry];
	const json_t* list = json_object_get(p->doc->root, "particles");
	const char* name = json_string_value(json_object_get(json_array_get(list, k), "name"));
	char path[PATH_CAPACITY], sub[PATH_CAPACITY], text[TEXT_QUOTED_CAPACITY];
	child_index(path, "particles", k);
	child_key(sub, path, "name");
	return fail(p, SM_ERROR_SCHEMA, sub,
	            "name %s reads as a reference to a particle of structure \"%.*s\": give the particle another "
	            "name",
	            sm_text_quoted(text, name), (int)length, structure);
}

// Structure `index` of "structures", obj, at path.
static bool read_structure(parser* p, const named_like_references* like, size_t index, const json_t* obj,
                           const char* path)
{
	static const char* const rope_keys[] = {"type",
	                                        "name",
	                                        "start",
	                                        "end",
	                                        "segments",
	                                        "mass",
	                                        "mass_per_length",
	                                        "structural",
	                                        "bending",
	                                        "mass_distribution",
	                                        NULL};
	static const char* const sheet_keys[] = {"type",       "name",  "origin", "edge_u",
	                                         "edge_v",     "nu",    "nv",     "mass",
	                                         "structural", "shear", "bend",   "mass_distribution",
	                                         NULL};
	static const char* const block_keys[] = {"type",
	                                         "name",
	                                         "origin",
	                                         "size",
	                                         "nu",
	                                         "nv",
	                                         "nw",
	                                         "mass",
	                                         "edge",
	                                         "face_diagonal",
	                                         "body_diagonal",
	                                         "mass_distribution",
	                                         NULL};
	static const char* const mesh_keys[] = {"type",   "name",    "vertices", "triangles", "file", "scale",
	                                        "origin", "density", "edge",     "bend",      NULL};
	char sub[PATH_CAPACITY];
	forget_parameters(p);
	if (!expect_object(p, obj, path) || !require(p, obj, path, "type") || !require(p, obj, path, "name"))
		return false;
	const json_t* type = json_object_get(obj, "type");
	const char* t = json_is_string(type) ? json_string_value(type) : "";
	child_key(sub, path, "type");
	document_structure s;
	if (strcmp(t, "rope") == 0)
		s.type = STRUCTURE_ROPE;
	else if (strcmp(t, "sheet") == 0)
		s.type = STRUCTURE_SHEET;
	else if (strcmp(t, "block") == 0)
		s.type = STRUCTURE_BLOCK;
	else if (strcmp(t, "mesh") == 0)
		s.type = STRUCTURE_MESH;
	else
		return fail(p, SM_ERROR_SCHEMA, sub, "must be \"rope\", \"sheet\", \"block\" or \"mesh\"");
	const char* const* keys[] = {rope_keys, sheet_keys, block_keys, mesh_keys};
	if (!check_keys(p, obj, path, keys[s.type]))
		return false;
	child_key(sub, path, "name");
	if (!check_name(p, json_object_get(obj, "name"), sub, true, &s.name))
		return false;
	const size_t name_bytes = strlen(s.name);
	char text[TEXT_QUOTED_CAPACITY];
	if (name_bytes > MAX_STRUCTURE_NAME_BYTES)
		return fail(p, SM_ERROR_SCHEMA, sub,
		            "structure name %s has %zu bytes; a structure's name may have at most %d, so that its "
		            "particles' names (name[row,column,layer]) fit in %d",
		            sm_text_quoted(text, s.name), name_bytes, MAX_STRUCTURE_NAME_BYTES, MAX_NAME_BYTES);
	if (find_structure(p->ex, s.name, name_bytes) != NULL)
		return fail(p, SM_ERROR_SCHEMA, sub, "structure name %s is already used",
		            sm_text_quoted(text, s.name));
	if (!check_names_against_structure(p, like, s.name, name_bytes))
		return false;

	sm_mass_distribution distribution = SM_MASS_EVEN;
	if (!read_distribution(p, obj, path, &distribution))
		return false;
	sm_model* model = p->ex->model;
	const int32_t p0 = sm_model_particle_count(model), s0 = sm_model_spring_count(model);
	const int64_t limit = p->doc->max_elements;
	spring_source groups[3] = {
	    {-1, -1, -1, -1, -1, false}, {-1, -1, -1, -1, -1, false}, {-1, -1, -1, -1, -1, false}};
	sm_status st = SM_OK;
	// A rope has no per-section constants; a sheet's and a mesh's springs stand for a width, a
	// block's for an area (docs/model-format.md).
	p->section_dimension = s.type == STRUCTURE_BLOCK ? 2 : s.type == STRUCTURE_ROPE ? 0 : 1;
	switch (s.type) {
	case STRUCTURE_ROPE: {
		sm_rope_def d = sm_default_rope_def();
		int64_t segments;
		if (!require(p, obj, path, "start") || !require(p, obj, path, "end") ||
		    !read_vector(p, FEEDS_STATE, obj, path, "start", ANY_FINITE, d.start, NULL) ||
		    !read_vector(p, FEEDS_STATE, obj, path, "end", ANY_FINITE, d.end, NULL) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "segments", 1, limit, &segments) ||
		    !read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !read_field(p, FEEDS_CONSTANTS, obj, path, "mass_per_length", POSITIVE, &d.mass_per_length,
		                NULL) ||
		    !read_material(p, obj, path, "structural", &d.structural, &groups[0]) ||
		    !read_material(p, obj, path, "bending", &d.bending, &groups[1]))
			return false;
		if (json_object_get(obj, "mass") != NULL && json_object_get(obj, "mass_per_length") != NULL)
			return fail(p, SM_ERROR_SCHEMA, path,
			            "give \"mass\" [kg] or \"mass_per_length\" [kg/m], not both");
		d.segments = (int32_t)segments;
		d.mass_distribution = distribution;
		const bool present[3] = {sm_structure_material_present(&d.structural),
		                         sm_structure_material_present(&d.bending), false};
		if (!check_budget(p, path, segments + 1, grid_springs(s.type, segments + 1, 1, 1, present)))
			return false;
		st = sm_add_rope(model, &d, &s.range);
		break;
	}
	case STRUCTURE_SHEET: {
		sm_sheet_def d = sm_default_sheet_def();
		d.structural = d.shear = d.bend = sm_default_spring_material();
		int64_t nu, nv;
		int32_t edge_sources[2][3];
		if (!read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, d.origin, NULL) ||
		    !read_vector(p, FEEDS_STATE, obj, path, "edge_u", ANY_FINITE, d.edge_u, edge_sources[0]) ||
		    !read_vector(p, FEEDS_STATE, obj, path, "edge_v", ANY_FINITE, d.edge_v, edge_sources[1]) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "nu", 2, limit, &nu) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "nv", 2, limit, &nv) ||
		    !read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !read_material(p, obj, path, "structural", &d.structural, &groups[0]) ||
		    !read_material(p, obj, path, "shear", &d.shear, &groups[1]) ||
		    !read_material(p, obj, path, "bend", &d.bend, &groups[2]))
			return false;
		static const char* const edge_keys[2] = {"edge_u", "edge_v"};
		for (int e = 0; e < 2; e++) {
			const double* edge = e == 0 ? d.edge_u : d.edge_v;
			if (edge[0] == 0.0 && edge[1] == 0.0 && edge[2] == 0.0) {
				char text[PATH_CAPACITY], vector[3 * DESCRIPTION_CAPACITY + 8];
				child_key(text, path, edge_keys[e]);
				return fail(p, SM_ERROR_INVALID_ARGUMENT, text,
				            "%s m is zero: the sheet spans no area and its particles would coincide",
				            describe_vector(p, vector, sizeof vector, edge, edge_sources[e]));
			}
		}
		const bool present[3] = {sm_structure_material_present(&d.structural),
		                         sm_structure_material_present(&d.shear),
		                         sm_structure_material_present(&d.bend)};
		if (!check_budget(p, path, nu * nv, grid_springs(s.type, nu, nv, 1, present)))
			return false;
		d.nu = (int32_t)nu;
		d.nv = (int32_t)nv;
		d.mass_distribution = distribution;
		st = sm_add_sheet(model, &d, &s.range);
		break;
	}
	case STRUCTURE_BLOCK: {
		sm_block_def d = sm_default_block_def();
		d.edge = d.face_diagonal = d.body_diagonal = sm_default_spring_material();
		int64_t nu, nv, nw;
		if (!require(p, obj, path, "size") ||
		    !read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, d.origin, NULL) ||
		    !read_vector(p, FEEDS_STATE, obj, path, "size", POSITIVE, d.size, NULL) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "nu", 2, limit, &nu) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "nv", 2, limit, &nv) ||
		    !read_count_field(p, FEEDS_COUNTS, obj, path, "nw", 2, limit, &nw) ||
		    !read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !read_material(p, obj, path, "edge", &d.edge, &groups[0]) ||
		    !read_material(p, obj, path, "face_diagonal", &d.face_diagonal, &groups[1]) ||
		    !read_material(p, obj, path, "body_diagonal", &d.body_diagonal, &groups[2]))
			return false;
		if (nu * nv > limit || nu * nv * nw > limit)
			return fail(p, SM_ERROR_SCHEMA, path, "%lld x %lld x %lld particles exceed the limit of %lld",
			            (long long)nu, (long long)nv, (long long)nw, (long long)limit);
		const bool present[3] = {sm_structure_material_present(&d.edge),
		                         sm_structure_material_present(&d.face_diagonal),
		                         sm_structure_material_present(&d.body_diagonal)};
		if (!check_budget(p, path, nu * nv * nw, grid_springs(s.type, nu, nv, nw, present)))
			return false;
		d.nu = (int32_t)nu;
		d.nv = (int32_t)nv;
		d.nw = (int32_t)nw;
		d.mass_distribution = distribution;
		st = sm_add_block(model, &d, &s.range);
		break;
	}
	case STRUCTURE_MESH: {
		sm_mesh_def d = sm_default_mesh_def();
		d.edge = sm_default_spring_material();
		double* vertices = NULL;
		int32_t* triangles = NULL;
		// The OBJ file of a "file", read when the document was parsed (read_mesh_files).
		const document_mesh_file* from =
		    json_object_get(obj, "file") != NULL && index < p->doc->mesh_file_slots
		        ? p->doc->mesh_files[index]
		        : NULL;
		double scale = 1.0, origin[3] = {0.0, 0.0, 0.0};
		bool ok =
		    (from != NULL || (require(p, obj, path, "vertices") && require(p, obj, path, "triangles"))) &&
		    read_field(p, FEEDS_CONSTANTS, obj, path, "density", POSITIVE, &d.density, NULL) &&
		    read_field(p, FEEDS_STATE, obj, path, "scale", POSITIVE, &scale, NULL) &&
		    read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, origin, NULL) &&
		    read_material(p, obj, path, "edge", &d.edge, &groups[0]) &&
		    read_material(p, obj, path, "bend", &d.bend, &groups[1]);
		if (ok && from != NULL) {
			d.vertex_count = from->mesh.vertex_count;
			d.triangle_count = from->mesh.triangle_count;
			vertices = malloc(3 * (size_t)(d.vertex_count > 0 ? d.vertex_count : 1) * sizeof(double));
			ok = check_budget(p, path, d.vertex_count, 0) &&
			     (vertices != NULL || fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for %d vertices",
			                               (int)d.vertex_count));
			if (ok)
				memcpy(vertices, from->mesh.vertices, 3 * (size_t)d.vertex_count * sizeof(double));
		} else if (ok)
			ok = read_mesh_arrays(p, obj, path, &vertices, &d.vertex_count, &triangles, &d.triangle_count);
		if (!ok) {
			free(vertices);
			free(triangles);
			return false;
		}
		// Vertex v at origin + scale v; a scale or an origin the file leaves out changes nothing (not
		// even the sign of a zero coordinate).
		const bool scaled = json_object_get(obj, "scale") != NULL,
		           moved = json_object_get(obj, "origin") != NULL;
		for (size_t k = 0; k < 3 * (size_t)d.vertex_count; k++) {
			if (scaled)
				vertices[k] *= scale;
			if (moved)
				vertices[k] += origin[k % 3];
		}
		d.vertices = vertices;
		d.triangles = from != NULL ? from->mesh.triangles : triangles;
		int32_t failed_triangle, failed_vertex;
		st = sm_add_mesh_located(model, &d, &s.range, &failed_triangle, &failed_vertex);
		// A triangle that repeats a vertex: named with the parameters its own vertex indices came
		// from, not with those of other triangles or of the vertices' positions, which have no part
		// in it.
		noted_parameters repeating = {{0}, 0, false};
		if (st == SM_ERROR_SELF_SPRING && from == NULL)
			note_repeating_triangle(p, obj, triangles, d.triangle_count, &repeating);
		free(vertices);
		free(triangles);
		if (st == SM_ERROR_SELF_SPRING && from == NULL)
			return fail_naming(p, st, path, sm_model_last_error(model), &repeating);
		// A failure about one triangle or vertex of an OBJ file: at the line of its face or vertex.
		const int32_t* place = from == NULL ? NULL
		                       : failed_triangle >= 0
		                           ? from->mesh.triangle_place + 2 * (size_t)failed_triangle
		                       : failed_vertex >= 0 ? from->mesh.vertex_place + 2 * (size_t)failed_vertex
		                                            : NULL;
		if (st != SM_OK && place != NULL) {
			char sub_file[PATH_CAPACITY], message[SM_ERROR_MESSAGE_CAPACITY];
			child_key(sub_file, path, "file");
			snprintf(message, sizeof message, "%s:%d:%d: %s", from->shown, (int)place[0], (int)place[1],
			         sm_model_last_error(model));
			return fail_naming_parameters(p, st, sub_file, message);
		}
		// The mesh's particles are within the limit; its springs are counted now.
		if (st == SM_OK && !check_budget(p, path, 0, 0))
			return false;
		break;
	}
	}
	p->section_dimension = 0;
	if (st != SM_OK)
		return fail_naming_parameters(p, st, path, sm_model_last_error(model));

	// Record the structure, name its particles and note the sources of its springs' constants.
	expansion* ex = p->ex;
	int32_t holder;
	void* spare;
	if (!GROW_ARRAY(ex->structures, &ex->structure_capacity, ex->structure_count + 1, spare))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory");
	ex->structures[ex->structure_count] = s;
	if (!sm_name_index_insert(&ex->structure_names, s.name, strlen(s.name), ex->structure_count, &holder))
		return fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory");
	ex->structure_count++;
	const sm_structure* r = &s.range;
	for (int32_t k = 0; k < r->particle_count; k++) {
		const int32_t index = p0 + k;
		p->ex->particle_sources[index] = (particle_source){-1, {-1, -1, -1}, {-1, -1, -1}};
		p->ex->name_offset[index] = -1;
		const int32_t column = k % r->shape[0], row = (k / r->shape[0]) % r->shape[1];
		const int32_t layer = k / (r->shape[0] * r->shape[1]);
		bool ok;
		if (s.type == STRUCTURE_SHEET)
			ok = name_particle(p, sub, index, "%s[%d,%d]", s.name, (int)row, (int)column);
		else if (s.type == STRUCTURE_BLOCK)
			ok = name_particle(p, sub, index, "%s[%d,%d,%d]", s.name, (int)row, (int)column, (int)layer);
		else
			ok = name_particle(p, sub, index, "%s[%d]", s.name, (int)k);
		if (!ok)
			return false;
	}
	for (int32_t k = 0; k < r->spring_count; k++)
		p->ex->spring_sources[s0 + k] = groups[spring_group(&s, model, s0 + k)];
	return true;
}

static bool read_structures(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "structures", "must be an array of structures, not %s",
		            type_name(list));
	named_like_references like = {.prefixes = NULL};
	sm_name_index_init(&like.index, named_like_prefix, &like);
	bool ok = find_names_like_references(p, &like);
	for (size_t k = 0; ok && k < json_array_size(list); k++) {
		char path[PATH_CAPACITY];
		child_index(path, "structures", k);
		ok = read_structure(p, &like, k, json_array_get(list, k), path);
	}
	named_like_free(&like);
	return ok;
}

// ---------------------------------------------------------------------------------------------
// Fixed particles, ports, settings.
// ---------------------------------------------------------------------------------------------

// "fixed": [reference, ..., {"min": [x, y, z], "max": [x, y, z]}, ...]; marks the particles
// in fix[].
static bool read_fixed_to(parser* p, const json_t* list, bool* fix)
{
	static const char* const box_keys[] = {"min", "max", NULL};
	const sm_model* model = p->ex->model;
	for (size_t k = 0; k < json_array_size(list); k++) {
		char path[PATH_CAPACITY];
		child_index(path, "fixed", k);
		const json_t* item = json_array_get(list, k);
		if (json_is_object(item)) {
			double lo[3], hi[3];
			int32_t lo_sources[3], hi_sources[3];
			if (!check_keys(p, item, path, box_keys) || !require(p, item, path, "min") ||
			    !require(p, item, path, "max") ||
			    !read_vector(p, FEEDS_MOTION, item, path, "min", ANY_FINITE, lo, lo_sources) ||
			    !read_vector(p, FEEDS_MOTION, item, path, "max", ANY_FINITE, hi, hi_sources))
				return false;
			// Every particle whose initial position is in the box, bounds included.
			int32_t count = 0;
			for (int32_t i = 0; i < model->particle_count; i++) {
				const double* x = model->position + 3 * (size_t)i;
				if (x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1] && x[2] >= lo[2] &&
				    x[2] <= hi[2]) {
					fix[i] = true;
					count++;
				}
			}
			char from[3 * DESCRIPTION_CAPACITY + 8], to[3 * DESCRIPTION_CAPACITY + 8];
			if (count == 0)
				return fail(p, SM_ERROR_SCHEMA, path, "the box from %s to %s contains no particle",
				            describe_vector(p, from, sizeof from, lo, lo_sources),
				            describe_vector(p, to, sizeof to, hi, hi_sources));
		} else {
			int32_t index;
			if (!resolve_particle(p, item, path, &index))
				return false;
			fix[index] = true;
		}
	}
	return true;
}

// "loads": constant forces on particles, [{"particle": REF, "force": [fx, fy, fz]}, ...]; the loads on
// one particle add up.
static bool read_loads(parser* p, const json_t* list)
{
	static const char* const keys[] = {"particle", "force", NULL};
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "loads", "must be an array of loads, not %s", type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return fail(p, SM_ERROR_SCHEMA, "loads", "too many loads (%zu)", n);
	p->ex->loads = calloc(n > 0 ? n : 1, sizeof(document_load));
	if (p->ex->loads == NULL)
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "loads", "out of memory");
	sm_model* model = p->ex->model;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		child_index(path, "loads", k);
		const json_t* obj = json_array_get(list, k);
		document_load* load = &p->ex->loads[k];
		child_key(sub, path, "particle");
		forget_parameters(p);
		if (!expect_object(p, obj, path) || !check_keys(p, obj, path, keys) ||
		    !require(p, obj, path, "particle") || !require(p, obj, path, "force") ||
		    !resolve_particle(p, json_object_get(obj, "particle"), sub, &load->particle) ||
		    !read_vector(p, FEEDS_CONSTANTS, obj, path, "force", ANY_FINITE, load->force, load->source))
			return false;
		p->ex->load_count++;
		sm_particle_def def;
		sm_model_get_particle(model, load->particle, &def);
		for (int c = 0; c < 3; c++)
			def.load[c] += load->force[c];
		// Loads on one particle whose sum is beyond a double are refused; the model names the particle.
		if (sm_model_set_particle(model, load->particle, &def) != SM_OK)
			return fail_naming_parameters(p, SM_ERROR_NOT_FINITE, path, sm_model_last_error(model));
	}
	return true;
}

// The particles of "fixed" are marked first and then fixed together (sm_model_set_motions), with
// the free particles numbered once.
static bool read_fixed(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "fixed", "must be an array of particle references and boxes, not %s",
		            type_name(list));
	sm_model* model = p->ex->model;
	bool* fix = calloc((size_t)model->particle_count + 1, sizeof(bool));
	if (fix == NULL)
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "fixed", "out of memory");
	const bool ok = read_fixed_to(p, list, fix);
	if (ok)
		sm_model_set_motions(model, fix, NULL, 0, SM_PARTICLE_FIXED);
	free(fix);
	return ok;
}

// Ports; port_at[i] is the first port on particle i (-1: none).
static bool read_ports_to(parser* p, const json_t* list, int32_t* port_at)
{
	static const char* const keys[] = {"name", "particle", "kind", NULL};
	const size_t n = json_array_size(list);
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		child_index(path, "ports", k);
		const json_t* obj = json_array_get(list, k);
		if (!expect_object(p, obj, path) || !check_keys(p, obj, path, keys) ||
		    !require(p, obj, path, "name") || !require(p, obj, path, "particle") ||
		    !require(p, obj, path, "kind"))
			return false;
		sm_port port;
		child_key(sub, path, "name");
		if (!check_name(p, json_object_get(obj, "name"), sub, true, &port.name))
			return false;
		const int32_t same_name = sm_name_index_find(&p->ex->port_names, port.name, strlen(port.name));
		char text[TEXT_QUOTED_CAPACITY];
		if (same_name >= 0)
			return fail(p, SM_ERROR_SCHEMA, sub, "port name %s is already used by ports[%d]",
			            sm_text_quoted(text, port.name), (int)same_name);
		child_key(sub, path, "particle");
		if (!resolve_particle(p, json_object_get(obj, "particle"), sub, &port.particle))
			return false;
		const json_t* kind = json_object_get(obj, "kind");
		const char* k_name = json_is_string(kind) ? json_string_value(kind) : "";
		child_key(sub, path, "kind");
		if (strcmp(k_name, "force") == 0)
			port.kind = SM_PORT_FORCE;
		else if (strcmp(k_name, "motion") == 0)
			port.kind = SM_PORT_MOTION;
		else if (strcmp(k_name, "probe") == 0)
			port.kind = SM_PORT_PROBE;
		else
			return fail(p, SM_ERROR_SCHEMA, sub, "must be \"force\", \"motion\" or \"probe\"");
		sm_particle_def def;
		sm_model_get_particle(p->ex->model, port.particle, &def);
		char which[TEXT_QUOTED_CAPACITY + 32];
		describe_particle(p->ex, port.particle, which, sizeof which);
		if (port.kind == SM_PORT_FORCE && def.motion != SM_PARTICLE_FREE)
			return fail(p, SM_ERROR_SCHEMA, path,
			            "a force port needs a free particle, and %s is fixed (use a motion or probe port)",
			            which);
		// Only probe ports share a particle, so a particle has one port of another kind or probes
		// alone, and its first port says which.
		const int32_t q = port_at[port.particle];
		if (q >= 0 && (p->ex->ports[q].kind != SM_PORT_PROBE || port.kind != SM_PORT_PROBE))
			return fail(p, SM_ERROR_SCHEMA, path,
			            "%s already has port %s; only probe ports may share a particle", which,
			            p->ex->ports[q].name);
		int32_t holder;
		p->ex->ports[p->ex->port_count] = port;
		if (!sm_name_index_insert(&p->ex->port_names, port.name, strlen(port.name), p->ex->port_count,
		                          &holder))
			return fail(p, SM_ERROR_OUT_OF_MEMORY, "ports", "out of memory");
		if (q < 0)
			port_at[port.particle] = p->ex->port_count;
		p->ex->port_count++;
	}
	return true;
}

static bool read_ports(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return fail(p, SM_ERROR_SCHEMA, "ports", "must be an array of ports, not %s", type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return fail(p, SM_ERROR_SCHEMA, "ports", "too many ports (%zu)", n);
	const int32_t particles = sm_model_particle_count(p->ex->model);
	p->ex->ports = calloc(n > 0 ? n : 1, sizeof(sm_port));
	int32_t* port_at = malloc((size_t)(particles > 0 ? particles : 1) * sizeof(int32_t));
	if (p->ex->ports == NULL || port_at == NULL) {
		free(port_at);
		return fail(p, SM_ERROR_OUT_OF_MEMORY, "ports", "out of memory");
	}
	for (int32_t i = 0; i < particles; i++)
		port_at[i] = -1;
	const bool ok = read_ports_to(p, list, port_at);
	free(port_at);
	return ok;
}

static bool read_choice(parser* p, const json_t* obj, const char* path, const char* key,
                        const char* const* names, int count, int* out)
{
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	child_key(sub, path, key);
	const char* s = json_is_string(value) ? json_string_value(value) : NULL;
	for (int k = 0; k < count && s != NULL; k++)
		if (names[k] != NULL && strcmp(names[k], s) == 0) {
			*out = k;
			return true;
		}
	char list[160] = "";
	size_t used = 0;
	for (int k = 0; k < count; k++) {
		if (names[k] == NULL)
			continue;
		int n = snprintf(list + used, sizeof list - used, "%s\"%s\"", used ? ", " : "", names[k]);
		if (n < 0 || (size_t)n >= sizeof list - used)
			break;
		used += (size_t)n;
	}
	return fail(p, SM_ERROR_SCHEMA, sub, "must be one of %s", list);
}

static bool read_settings(parser* p, const json_t* simulation, const json_t* fmu)
{
	static const char* const keys[] = {"stop_time",     "output_interval", "rtol",      "atol",
	                                   "atol_position", "atol_velocity",   "method",    "solver",
	                                   "jacobian",      "max_step",        "max_steps", NULL};
	static const char* const fmu_keys[] = {"particle_variables", NULL};
	sm_document_settings* s = &p->ex->settings;
	s->stop_time = 1.0;
	s->output_interval = 0.01;
	s->solver = sm_default_simulation_def();
	s->particle_variables = true;
	if (simulation != NULL) {
		const char* path = "simulation";
		if (!expect_object(p, simulation, path) || !check_keys(p, simulation, path, keys))
			return false;
		sm_simulation_def* d = &s->solver;
		double atol = -1.0;
		if (!read_field(p, FEEDS_SETTINGS, simulation, path, "stop_time", POSITIVE, &s->stop_time, NULL) ||
		    !read_field(p, FEEDS_SETTINGS, simulation, path, "output_interval", POSITIVE, &s->output_interval,
		                NULL) ||
		    !read_field(p, FEEDS_SETTINGS, simulation, path, "rtol", FRACTION, &d->relative_tolerance,
		                NULL) ||
		    !read_field(p, FEEDS_SETTINGS, simulation, path, "atol", TOLERANCE, &atol, NULL) ||
		    !read_field(p, FEEDS_SETTINGS, simulation, path, "max_step", STEP_CAP, &d->max_step, NULL))
			return false;
		if (atol > 0.0)
			d->absolute_tolerance_position = d->absolute_tolerance_velocity = atol;
		if (!read_field(p, FEEDS_SETTINGS, simulation, path, "atol_position", TOLERANCE,
		                &d->absolute_tolerance_position, NULL) ||
		    !read_field(p, FEEDS_SETTINGS, simulation, path, "atol_velocity", TOLERANCE,
		                &d->absolute_tolerance_velocity, NULL))
			return false;
		if (json_object_get(simulation, "max_steps") != NULL) {
			int64_t steps;
			if (!read_count(p, FEEDS_SETTINGS, json_object_get(simulation, "max_steps"),
			                "simulation.max_steps", 1, INT32_MAX, &steps))
				return false;
			d->max_steps = (int32_t)steps;
		}
		const char* const methods[] = {sm_method_name(SM_METHOD_BDF), sm_method_name(SM_METHOD_ADAMS)};
		const char* const jacobians[] = {sm_jacobian_variant_name(SM_JACOBIAN_EXACT),
		                                 sm_jacobian_variant_name(SM_JACOBIAN_DEFINITE)};
		const char* solvers[SM_SOLVER_COUNT];
		for (int k = 0; k < SM_SOLVER_COUNT; k++)
			solvers[k] = sm_linear_solver_name((sm_linear_solver)k);
		int method = (int)d->method, jacobian = (int)d->jacobian, solver = (int)d->solver;
		if (!read_choice(p, simulation, path, "method", methods, 2, &method) ||
		    !read_choice(p, simulation, path, "jacobian", jacobians, 2, &jacobian) ||
		    !read_choice(p, simulation, path, "solver", solvers, SM_SOLVER_COUNT, &solver))
			return false;
		d->method = (sm_method)method;
		d->jacobian = (sm_jacobian_variant)jacobian;
		d->solver = (sm_linear_solver)solver;
	}
	if (fmu != NULL) {
		if (!expect_object(p, fmu, "fmu") || !check_keys(p, fmu, "fmu", fmu_keys) ||
		    !read_bool(p, fmu, "fmu", "particle_variables", &s->particle_variables))
			return false;
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Evaluation of the whole document.
// ---------------------------------------------------------------------------------------------

// Evaluates the document's tree with the given parameter values into a new expansion.
static expansion* expand(const sm_document* doc, const double* parameter_values, sm_error* err)
{
	parser p = {
	    .doc = doc, .parameter_values = parameter_values, .err = err, .ex = calloc(1, sizeof(expansion))};
	if (p.ex == NULL) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", doc->source);
		return NULL;
	}
	const size_t parameters = doc->parameter_count > 0 ? (size_t)doc->parameter_count : 1;
	p.ex->parameter_uses = calloc(parameters, 1);
	p.ex->parameter_units = calloc(parameters, sizeof(const char*));
	if (p.ex->parameter_uses == NULL || p.ex->parameter_units == NULL) {
		free(p.ex->parameter_uses);
		free(p.ex->parameter_units);
		free(p.ex);
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", doc->source);
		return NULL;
	}
	sm_name_index_init(&p.ex->particle_names, particle_name, p.ex);
	sm_name_index_init(&p.ex->structure_names, structure_name, p.ex);
	sm_name_index_init(&p.ex->port_names, port_name, p.ex);
	const json_t* root = doc->root;
	sm_model_def def = sm_default_model_def();
	int32_t gravity_source[3];
	bool ok =
	    read_vector(&p, FEEDS_CONSTANTS, root, "", "gravity", ANY_FINITE, def.gravity, gravity_source) &&
	    read_field(&p, FEEDS_CONSTANTS, root, "", "mass_damping", NON_NEGATIVE, &def.mass_damping, NULL);
	if (ok) {
		sm_error model_err;
		p.ex->model = sm_model_create(&def, &model_err);
		if (p.ex->model == NULL)
			ok = fail(&p, model_err.status, "", "%s", model_err.message);
	}
	ok = ok && read_particles(&p, json_object_get(root, "particles")) &&
	     read_structures(&p, json_object_get(root, "structures")) &&
	     read_springs(&p, json_object_get(root, "springs")) &&
	     read_fixed(&p, json_object_get(root, "fixed")) && read_loads(&p, json_object_get(root, "loads")) &&
	     read_ports(&p, json_object_get(root, "ports")) &&
	     read_settings(&p, json_object_get(root, "simulation"), json_object_get(root, "fmu"));
	if (ok && sm_model_particle_count(p.ex->model) == 0)
		ok = fail(&p, SM_ERROR_SCHEMA, "",
		          "the model has no particles (give \"particles\" or \"structures\")");
	if (ok && doc->initial_position != NULL) {
		sm_model* model = p.ex->model;
		const int32_t n = sm_model_particle_count(model);
		if (n != doc->initial_count)
			ok = fail(&p, SM_ERROR_TOPOLOGY, "",
			          "the model now has %d particles but its initial state was set for %d", (int)n,
			          (int)doc->initial_count);
		for (int32_t i = 0; ok && i < n; i++) {
			sm_particle_def d;
			sm_model_get_particle(model, i, &d);
			memcpy(d.position, doc->initial_position + 3 * (size_t)i, sizeof d.position);
			memcpy(d.velocity, doc->initial_velocity + 3 * (size_t)i, sizeof d.velocity);
			if (sm_model_set_particle(model, i, &d) != SM_OK)
				ok = fail(&p, SM_ERROR_NOT_FINITE, "", "initial state: %s", sm_model_last_error(model));
		}
	}
	if (!ok) {
		expansion_free(p.ex);
		return NULL;
	}
	return p.ex;
}

static bool read_header(sm_document* doc, sm_error* err)
{
	static const char* const keys[] = {"springmass",   "name",      "description", "parameters", "gravity",
	                                   "mass_damping", "particles", "springs",     "structures", "fixed",
	                                   "loads",        "ports",     "simulation",  "fmu",        NULL};
	parser p = {.doc = doc, .err = err};
	const json_t* root = doc->root;
	if (!json_is_object(root))
		return fail(&p, SM_ERROR_SCHEMA, "", "a model file is a JSON object, not %s", type_name(root));
	if (!check_keys(&p, root, "", keys))
		return false;
	const json_t* version = json_object_get(root, "springmass");
	if (version == NULL)
		return fail(&p, SM_ERROR_SCHEMA, "",
		            "missing \"springmass\": %d (the format version; is this a springmass model file?)",
		            SM_FORMAT_VERSION);
	if (!json_is_integer(version))
		return fail(&p, SM_ERROR_SCHEMA, "springmass", "format version must be the integer %d, not %s",
		            SM_FORMAT_VERSION,
		            json_is_string(version) ? "a string (no quotes)"
		            : json_is_real(version) ? "a real number"
		                                    : "that");
	if (json_integer_value(version) != SM_FORMAT_VERSION)
		return fail(&p, SM_ERROR_SCHEMA, "springmass",
		            "format version must be %d (this build reads version %d)", SM_FORMAT_VERSION,
		            SM_FORMAT_VERSION);
	if (!require(&p, root, "", "name") ||
	    !check_name(&p, json_object_get(root, "name"), "name", true, &doc->name))
		return false;
	const json_t* description = json_object_get(root, "description");
	doc->description = "";
	if (description != NULL) {
		if (!json_is_string(description))
			return fail(&p, SM_ERROR_SCHEMA, "description", "must be a string, not %s",
			            type_name(description));
		doc->description = json_string_value(description);
		int64_t position;
		const int32_t c = sm_text_find_refused(doc->description, sm_text_refused_in_description, &position);
		if (c >= 0 && sm_text_is_line_break(c))
			return fail(&p, SM_ERROR_SCHEMA, "description",
			            "must be one line: it has a line break, U+%04X, at character %lld", (unsigned)c,
			            (long long)position);
		if (c >= 0)
			return fail(&p, SM_ERROR_SCHEMA, "description",
			            "has a control character, U+%04X, at character %lld (a tab is the only one allowed)",
			            (unsigned)c, (long long)position);
	}
	const json_t* parameters = json_object_get(root, "parameters");
	if (parameters == NULL)
		return true;
	if (!expect_object(&p, parameters, "parameters"))
		return false;
	const size_t n = json_object_size(parameters);
	doc->parameter_names = calloc(n > 0 ? n : 1, sizeof(char*));
	doc->parameter_values = calloc(n > 0 ? n : 1, sizeof(double));
	if (doc->parameter_names == NULL || doc->parameter_values == NULL)
		return fail(&p, SM_ERROR_OUT_OF_MEMORY, "parameters", "out of memory");
	const char* key;
	json_t* value;
	json_object_foreach((json_t*)parameters, key, value)
	{
		// The key is escaped in the path as in the messages about it, and cut at a character
		// before the 50 bytes child_key keeps of it.
		char path[PATH_CAPACITY], escaped[50];
		if (!sm_text_escape(escaped, sizeof escaped - 4, key))
			strcat(escaped, "...");
		child_key(path, "parameters", escaped);
		if (!check_name_text(&p, key, strlen(key), path, true))
			return false;
		if (!json_is_number(value))
			return fail(&p, SM_ERROR_SCHEMA, path, "a parameter's value must be a number, not %s",
			            type_name(value));
		const double v = json_number_value(value);
		if (!isfinite(v))
			return fail(&p, SM_ERROR_NOT_FINITE, path, "%g is not finite", v);
		doc->parameter_names[doc->parameter_count] = key;
		doc->parameter_values[doc->parameter_count] = v;
		int32_t holder;  // the JSON parser refused repeated keys
		if (!sm_name_index_insert(&doc->parameter_index, key, strlen(key), doc->parameter_count, &holder))
			return fail(&p, SM_ERROR_OUT_OF_MEMORY, "parameters", "out of memory");
		doc->parameter_count++;
	}
	return true;
}

// Whether the parser stopped before the byte its error is about (error.position: bytes read),
// without reading it: a byte that begins no UTF-8 character, or a control character in a string
// (a line end there among them). The error is then at that byte, not at the character before.
static bool error_before_its_byte(const json_error_t* error, const char* text, size_t length)
{
	if (error->position < 0 || (size_t)error->position >= length)
		return false;
	const unsigned char c = (unsigned char)text[error->position];
	if (json_error_code(error) == json_error_invalid_utf8)
		return c >= 0x80;
	const bool control = strncmp(error->text, "control character ", 18) == 0 ||
	                     strncmp(error->text, "unexpected newline", 18) == 0;
	return json_error_code(error) == json_error_invalid_syntax && c < 0x20 && control;
}

// Where the token an error names whole begins, as the offset of its first byte; `at` (the bytes the
// parser read, up to the token's last) for any other error. A token the parser quotes whole ("'}'
// expected near '\"name\"'", "invalid token near 'NaN'", a repeated key, a number out of range)
// is reported at its first character, where an editor's cursor should go to mend it; an error
// inside a string (an escape, a control character) stays at the character at fault.
static size_t token_start(const json_error_t* error, const char* text, size_t at)
{
	const enum json_error_code code = json_error_code(error);
	const bool whole =
	    code == json_error_duplicate_key || code == json_error_numeric_overflow ||
	    (code == json_error_invalid_syntax && (strstr(error->text, " expected near '") != NULL ||
		                                       strncmp(error->text, "invalid token near '", 20) == 0 ||
		                                       strncmp(error->text, "unexpected token near '", 23) == 0));
	const char* near = strstr(error->text, " near '");
	if (!whole || near == NULL)
		return at;
	const char* token = near + 7;
	const size_t quoted = strlen(token);
	// The quoted text is the token's bytes, unless the message was cut short.
	if (quoted < 2 || token[quoted - 1] != '\'' || quoted - 1 > at ||
	    memcmp(text + at - (quoted - 1), token, quoted - 1) != 0)
		return at;
	return at - (quoted - 1);
}

// Value of the four hexadecimal digits at s (the parser checked that they are).
static unsigned hex4(const char* s)
{
	unsigned v = 0;
	for (int k = 0; k < 4; k++) {
		const char c = s[k];
		v = 16 * v + (unsigned)(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10);
	}
	return v;
}

// Where the escape at fault begins, for the errors the parser finds only once it has read a
// string to its closing quote (a \u0000, or a \u escape of half a surrogate pair without its other
// half): the parser's position is then past that quote, which may be far from the escape it
// names. The escape is the first such one in the string, as the parser decodes them in order.
// `at` (the bytes the parser read) for any other error.
static size_t escape_at_fault(const json_error_t* error, const char* text, size_t at)
{
	const enum json_error_code code = json_error_code(error);
	if (!(code == json_error_null_character || code == json_error_null_byte_in_key ||
	      (code == json_error_invalid_syntax && strncmp(error->text, "invalid Unicode '", 17) == 0)) ||
	    at < 2 || text[at - 1] != '"')
		return at;
	// The opening quote: the first '"' before the closing one that no backslash escapes.
	size_t open = at - 1;
	for (;;) {
		if (open == 0)
			return at;
		open--;
		size_t backslashes = 0;
		while (backslashes < open && text[open - 1 - backslashes] == '\\')
			backslashes++;
		if (text[open] == '"' && backslashes % 2 == 0)
			break;
	}
	for (size_t i = open + 1; i + 6 < at; i++) {
		if (text[i] != '\\')
			continue;
		if (text[i + 1] != 'u') {
			i++;  // a one-character escape
			continue;
		}
		const unsigned v = hex4(text + i + 2);
		if (v >= 0xd800 && v <= 0xdbff && i + 12 < at && text[i + 6] == '\\' && text[i + 7] == 'u') {
			const unsigned low = hex4(text + i + 8);
			if (low >= 0xdc00 && low <= 0xdfff) {
				i += 11;  // a whole pair
				continue;
			}
		}
		if (v == 0 || (v >= 0xd800 && v <= 0xdfff))
			return i;
		i += 5;
	}
	return at;
}

// Whether a syntax error reads as a missing comma: the parser expected the end of an array or an
// object and found the start of another value ("']' expected near '\"springs\"'").
static bool missing_comma(const char* message)
{
	static const char* const closing[] = {"']' expected near '", "'}' expected near '"};
	for (int k = 0; k < 2; k++) {
		const size_t length = strlen(closing[k]);
		if (strncmp(message, closing[k], length) == 0) {
			const char c = message[length];
			return c == '"' || c == '{' || c == '[' || c == '-' || (c >= '0' && c <= '9') || c == 't' ||
			       c == 'f' || c == 'n';
		}
	}
	return false;
}

static sm_status read_regular_file(const char* path, const char* shown, char** text, size_t* length,
                                   sm_error* err);

// The OBJ files of the meshes that give a "file" (a path relative to `folder`, NULL or "" for the
// current directory, unless absolute), read once, when the document is parsed: changing a
// parameter builds the meshes again from what was read. A list of structures that is not one, or
// a structure that is no mesh, is left for expand() to name.
static bool read_mesh_files(sm_document* doc, const char* folder, sm_error* err)
{
	parser p = {.doc = doc, .err = err};
	const json_t* list = json_object_get(doc->root, "structures");
	if (!json_is_array(list))
		return true;
	const size_t n = json_array_size(list);
	doc->mesh_files = calloc(n > 0 ? n : 1, sizeof *doc->mesh_files);
	if (doc->mesh_files == NULL)
		return fail(&p, SM_ERROR_OUT_OF_MEMORY, "structures", "out of memory");
	doc->mesh_file_slots = n;
	// As many triangles as a closed surface of the most vertices a model may have (twice as many),
	// within what the mesh builder takes.
	const int64_t max_triangles = 2 * doc->max_elements < SM_STRUCTURE_MAX_ELEMENTS / 3
	                                  ? 2 * doc->max_elements
	                                  : SM_STRUCTURE_MAX_ELEMENTS / 3;
	for (size_t k = 0; k < n; k++) {
		const json_t* obj = json_array_get(list, k);
		const json_t* type = json_object_get(obj, "type");
		const json_t* file = json_object_get(obj, "file");
		if (file == NULL || !json_is_string(type) || strcmp(json_string_value(type), "mesh") != 0)
			continue;
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		child_index(path, "structures", k);
		child_key(sub, path, "file");
		if (!json_is_string(file))
			return fail(&p, SM_ERROR_SCHEMA, sub, "must be a string, the path of an OBJ file, not %s",
			            type_name(file));
		if (json_object_get(obj, "vertices") != NULL || json_object_get(obj, "triangles") != NULL)
			return fail(&p, SM_ERROR_SCHEMA, path,
			            "give \"file\" (an OBJ file) or \"vertices\" and \"triangles\", not both");
		const char* name = json_string_value(file);
		if (name[0] == '\0')
			return fail(&p, SM_ERROR_SCHEMA, sub, "must name an OBJ file, not be empty");
		// A relative path is the model file's folder's.
		const size_t folder_bytes = folder != NULL && name[0] != '/' ? strlen(folder) : 0;
		const bool slash = folder_bytes > 0 && folder[folder_bytes - 1] != '/';
		char* joined = malloc(folder_bytes + slash + strlen(name) + 1);
		document_mesh_file* f = calloc(1, sizeof *f);
		if (f != NULL)
			doc->mesh_files[k] = f;
		if (joined == NULL || f == NULL || (f->shown = malloc(SM_ERROR_MESSAGE_CAPACITY / 2 + 1)) == NULL) {
			free(joined);
			return fail(&p, SM_ERROR_OUT_OF_MEMORY, sub, "out of memory");
		}
		if (folder_bytes > 0)
			memcpy(joined, folder, folder_bytes);
		if (slash)
			joined[folder_bytes] = '/';
		strcpy(joined + folder_bytes + slash, name);
		sm_text_shown(f->shown, SM_ERROR_MESSAGE_CAPACITY / 2, joined);
		char* text = NULL;
		size_t length = 0;
		sm_error file_err = {SM_OK, ""};
		const sm_status read = read_regular_file(joined, f->shown, &text, &length, &file_err);
		free(joined);
		if (read != SM_OK)
			return fail(&p, read, sub, "%s", file_err.message);
		int line, column;
		char message[MESH_FILE_MESSAGE_CAPACITY];
		const sm_status st = sm_mesh_file_parse(text, length, doc->max_elements, max_triangles, &f->mesh,
		                                        &line, &column, message);
		free(text);
		if (st != SM_OK && line > 0)
			return fail(&p, st, sub, "%s:%d:%d: %s", f->shown, line, column, message);
		if (st != SM_OK)
			return fail(&p, st, sub, "%s: %s", f->shown, message);
	}
	return true;
}

// sm_document_parse_limited, with the OBJ files of meshes found relative to `folder`.
static sm_document* parse_document(const char* text, size_t length, const char* source_name,
                                   const char* folder, int64_t max_elements, sm_error* err)
{
	sm_error_clear(err);
	if (source_name == NULL)
		source_name = "<model>";
	if (text == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "%s: no text to parse", source_name);
		return NULL;
	}
	sm_document* doc = calloc(1, sizeof *doc);
	if (doc == NULL || (doc->source = malloc(strlen(source_name) + 1)) == NULL) {
		free(doc);
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", source_name);
		return NULL;
	}
	strcpy(doc->source, source_name);
	doc->max_elements = max_elements;
	sm_name_index_init(&doc->parameter_index, parameter_name, doc);
	// A UTF-8 byte-order mark may open the text (RFC 8259, section 8.1, lets a parser ignore
	// it). Editors do not show it, so skipping it keeps line 1's columns as they see them.
	if (length >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0) {
		text += 3;
		length -= 3;
	}
	// A NUL byte ends the text for the JSON parser, which then reports what it misses at the
	// end; say where the NUL is instead.
	const char* nul = memchr(text, '\0', length);
	if (nul != NULL) {
		int line, column;
		sm_text_position(text, length, (size_t)(nul - text) + 1, &line, &column);
		sm_error_set(err, SM_ERROR_SYNTAX,
		             "%s:%d:%d: a NUL byte (a model file is UTF-8 text without NUL bytes)", source_name, line,
		             column);
		sm_document_destroy(doc);
		return NULL;
	}
	size_t blank = 0;
	while (blank < length && strchr(" \t\r\n", text[blank]) != NULL)
		blank++;
	if (blank == length) {
		sm_error_set(err, SM_ERROR_SYNTAX, "%s: the model file is empty (a model file is one JSON object)",
		             source_name);
		sm_document_destroy(doc);
		return NULL;
	}
	// The parser reads its numbers in the C locale whatever LC_NUMERIC the calling thread has.
	// Before each real number it asks localeconv() for the decimal point, and glibc's localeconv()
	// fills one static structure for the whole process: a thread under a decimal comma (uselocale)
	// and another under a '.' parsing at once read each other's point, and the parser aborted the
	// process on "9.81" read as 9. In the C locale every parse writes and reads the same '.'.
	const sm_c_locale_scope scope = sm_enter_c_locale();
	if (!sm_c_locale_entered(scope)) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory for the C locale", source_name);
		sm_document_destroy(doc);
		return NULL;
	}
	json_error_t error;
	doc->root = json_loadb(text, length, JSON_REJECT_DUPLICATES, &error);
	sm_leave_c_locale(scope);
	if (doc->root == NULL) {
		// Line and column from the parser's byte position: the parser ends lines at LF only, so
		// that a file with lone CRs (old Mac line ends) would be all on line 1. Its message quotes
		// the text near the error, which may hold what a terminal would act on: shown escaped.
		const enum json_error_code code = json_error_code(&error);
		int line, column;
		// Where the parser stopped before the byte at fault, the error is at that byte: past it,
		// so that a line end there begins the next line. A stray continuation byte is a
		// character of its own there, which sm_text_position, counting characters, does not count.
		const size_t at = (size_t)error.position;
		const bool before = error_before_its_byte(&error, text, length);
		const size_t escape = escape_at_fault(&error, text, at);
		const size_t start = before ? at : escape < at ? escape : token_start(&error, text, at);
		sm_text_position(text, length, before ? at + 1 : start < at ? start + 1 : at, &line, &column);
		if (before && ((unsigned char)text[at] & 0xc0) == 0x80)
			column++;
		char shown[6 * JSON_ERROR_TEXT_LENGTH + 1];
		sm_text_shown(shown, sizeof shown - 1, error.text);
		if (code == json_error_null_character || code == json_error_null_byte_in_key)
			sm_error_set(err, SM_ERROR_SYNTAX, "%s:%d:%d: strings in a model file may not contain \\u0000",
			             source_name, line, column);
		else
			sm_error_set(err, SM_ERROR_SYNTAX, "%s:%d:%d: %s%s", source_name, line, column, shown,
			             missing_comma(error.text) ? " (or a ',' before it)" : "");
		sm_document_destroy(doc);
		return NULL;
	}
	if (!read_header(doc, err) || !read_mesh_files(doc, folder, err) ||
	    (doc->current = expand(doc, doc->parameter_values, err)) == NULL) {
		sm_document_destroy(doc);
		return NULL;
	}
	return doc;
}

sm_document* sm_document_parse_limited(const char* text, size_t length, const char* source_name,
                                       int64_t max_elements, sm_error* err)
{
	return parse_document(text, length, source_name, NULL, max_elements, err);
}

sm_document* sm_document_parse(const char* text, size_t length, const char* source_name, sm_error* err)
{
	return parse_document(text, length, source_name, NULL, SM_DOCUMENT_MAX_ELEMENTS, err);
}

sm_document* sm_document_parse_in_folder(const char* text, size_t length, const char* source_name,
                                         const char* folder, sm_error* err)
{
	return parse_document(text, length, source_name, folder, SM_DOCUMENT_MAX_ELEMENTS, err);
}

// read(), again when a signal interrupts it.
static ssize_t read_some(int fd, char* buffer, size_t size)
{
	ssize_t got;
	do
		got = read(fd, buffer, size);
	while (got < 0 && errno == EINTR);
	return got;
}

// Reads the whole of the open regular file fd into *text (NUL-terminated, *length bytes). Its
// size from fstat is only a first guess: a file in /proc says 0 and has text, and a file may
// grow while it is read. Once the buffer is full, one byte more is asked for: none is the end,
// one means growing the buffer, unless the text would pass MAX_FILE_BYTES.
static sm_status read_all(int fd, off_t size, const char* path, char** text, size_t* length, sm_error* err)
{
	size_t capacity = (size_t)size + 1, used = 0;
	char* data = malloc(capacity);
	while (data != NULL) {
		const bool full = used + 1 == capacity;
		const ssize_t got = read_some(fd, data + used, full ? 1 : capacity - 1 - used);
		if (got < 0) {
			const int error = errno;
			free(data);
			return sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: %s", path, strerror(error));
		}
		if (got == 0)
			break;
		used += (size_t)got;
		if (!full)
			continue;
		// The byte read took the NUL's place: grow, unless the text is now too long.
		if (used > (size_t)MAX_FILE_BYTES) {
			free(data);
			return sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: larger than %ld bytes", path,
			                    MAX_FILE_BYTES);
		}
		capacity = 2 * capacity > 4096 ? 2 * capacity : 4096;
		if (capacity > (size_t)MAX_FILE_BYTES + 1)
			capacity = (size_t)MAX_FILE_BYTES + 1;
		char* grown = realloc(data, capacity);
		if (grown == NULL)
			free(data);
		data = grown;
	}
	if (data == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory for %zu bytes", path, capacity);
	data[used] = '\0';
	*text = data;
	*length = used;
	return SM_OK;
}

// Only a regular file is read. It is opened without waiting (O_NONBLOCK), so that a FIFO
// without a writer is refused at once rather than blocking the open for ever, and its type is
// checked before the first read: a device such as /dev/zero would be read without end. Messages
// name the file `shown`.
static sm_status read_regular_file(const char* path, const char* shown, char** text, size_t* length,
                                   sm_error* err)
{
	*text = NULL;
	*length = 0;
	const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return sm_error_set(err, SM_ERROR_FILE, "%s: cannot open: %s", shown, strerror(errno));
	struct stat st;
	sm_status status = SM_ERROR_FILE;
	if (fstat(fd, &st) != 0)
		sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: %s", shown, strerror(errno));
	else if (S_ISDIR(st.st_mode))
		sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: %s", shown, strerror(EISDIR));
	else if (!S_ISREG(st.st_mode))
		sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: not a regular file", shown);
	else if (st.st_size > MAX_FILE_BYTES)
		sm_error_set(err, SM_ERROR_FILE, "%s: cannot read: larger than %ld bytes", shown, MAX_FILE_BYTES);
	else
		status = read_all(fd, st.st_size, shown, text, length, err);
	close(fd);
	return status;
}

sm_document* sm_document_load(const char* path, sm_error* err)
{
	sm_error_clear(err);
	if (path == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "no model file given");
		return NULL;
	}
	char* text = NULL;
	size_t length = 0;
	if (read_regular_file(path, path, &text, &length, err) != SM_OK)
		return NULL;
	// The OBJ files a model names are found beside it: in the folder of its path.
	const char* slash = strrchr(path, '/');
	const size_t folder_bytes = slash == NULL ? 0 : slash == path ? 1 : (size_t)(slash - path);
	char* folder = malloc(folder_bytes + 1);
	sm_document* doc = NULL;
	if (folder == NULL)
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
	else {
		memcpy(folder, path, folder_bytes);
		folder[folder_bytes] = '\0';
		doc = parse_document(text, length, path, folder, SM_DOCUMENT_MAX_ELEMENTS, err);
	}
	free(folder);
	free(text);
	return doc;
}

void sm_document_destroy(sm_document* doc)
{
	if (doc == NULL)
		return;
	expansion_free(doc->current);
	json_decref(doc->root);
	free(doc->parameter_names);
	sm_name_index_free(&doc->parameter_index);
	free(doc->parameter_values);
	free(doc->initial_position);
	free(doc->initial_velocity);
	for (size_t k = 0; k < doc->mesh_file_slots; k++) {
		if (doc->mesh_files[k] == NULL)
			continue;
		sm_mesh_file_free(&doc->mesh_files[k]->mesh);
		free(doc->mesh_files[k]->shown);
		free(doc->mesh_files[k]);
	}
	free(doc->mesh_files);
	free(doc->source);
	free(doc);
}

// ---------------------------------------------------------------------------------------------
// Accessors.
// ---------------------------------------------------------------------------------------------

const char* sm_document_name(const sm_document* doc)
{
	return doc != NULL ? doc->name : NULL;
}

const char* sm_document_description(const sm_document* doc)
{
	return doc != NULL ? doc->description : NULL;
}

sm_status sm_document_build(const sm_document* doc, sm_model** model, sm_error* err)
{
	sm_error_clear(err);
	if (model == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_build: no place for the model");
	*model = NULL;
	if (doc == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_build: no document");
	*model = sm_model_clone(doc->current->model);
	if (*model == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory for the model", doc->source);
	return SM_OK;
}

int32_t sm_document_parameter_count(const sm_document* doc)
{
	return doc != NULL ? doc->parameter_count : 0;
}

const char* sm_document_parameter_name(const sm_document* doc, int32_t index)
{
	return doc != NULL && index >= 0 && index < doc->parameter_count ? doc->parameter_names[index] : NULL;
}

double sm_document_parameter_value(const sm_document* doc, int32_t index)
{
	return doc != NULL && index >= 0 && index < doc->parameter_count ? doc->parameter_values[index] : NAN;
}

const char* sm_document_parameter_unit(const sm_document* doc, int32_t index)
{
	if (doc == NULL || index < 0 || index >= doc->parameter_count)
		return NULL;
	const char* unit = doc->current->parameter_units[index];
	return unit != NULL ? unit : no_single_unit;
}

uint32_t sm_document_parameter_uses(const sm_document* doc, int32_t index)
{
	return doc != NULL && index >= 0 && index < doc->parameter_count ? doc->current->parameter_uses[index]
	                                                                 : 0;
}

int32_t sm_document_parameter_index(const sm_document* doc, const char* name)
{
	return doc != NULL && name != NULL ? find_parameter(doc, name) : -1;
}

// A parameter keeps its value only when the new one is the same double, down to the sign of a zero:
// -0 and 0 compare equal, but a file that gives -0.0 builds a model with -0 where it gives 0 a +0
// (a position or velocity, which the saved file and `springmass run`'s CSV then write "-0"), and
// setting a parameter is giving the file its value.
static bool same_value(double a, double b)
{
	return a == b && signbit(a) == signbit(b);
}

sm_status sm_document_set_parameters(sm_document* doc, const double* values, sm_error* err)
{
	sm_error_clear(err);
	if (doc == NULL || (values == NULL && doc->parameter_count > 0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_set_parameters: no %s",
		                    doc == NULL ? "document" : "values");
	bool changed = false;
	for (int32_t k = 0; k < doc->parameter_count; k++) {
		if (!isfinite(values[k]))
			return sm_error_set(err, SM_ERROR_NOT_FINITE, "%s: parameters.%s: %g is not finite", doc->source,
			                    doc->parameter_names[k], values[k]);
		changed = changed || !same_value(values[k], doc->parameter_values[k]);
	}
	if (!changed)
		return SM_OK;
	double* copy = malloc((size_t)doc->parameter_count * sizeof(double));
	if (copy == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", doc->source);
	memcpy(copy, values, (size_t)doc->parameter_count * sizeof(double));
	sm_error local = {SM_OK, ""};
	expansion* ex = expand(doc, copy, &local);
	if (ex == NULL) {
		// Name the parameters that changed, as the loader names those a value came from ("(with
		// parameter a = 1 and parameter b = 2)"), unless the message already names one of them.
		int32_t last = -1;
		bool named = false;
		for (int32_t k = 0; k < doc->parameter_count; k++) {
			if (same_value(copy[k], doc->parameter_values[k]))
				continue;
			char name[300];
			snprintf(name, sizeof name, "parameter %s = ", doc->parameter_names[k]);
			named = named || strstr(local.message, name) != NULL;
			last = k;
		}
		char with[SM_ERROR_MESSAGE_CAPACITY] = "";
		size_t used = 0;
		for (int32_t k = 0, n = 0; k < doc->parameter_count && !named && used < sizeof with; k++) {
			if (same_value(copy[k], doc->parameter_values[k]))
				continue;
			const char* joint = n++ == 0 ? " (with " : k == last ? " and " : ", ";
			char value[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(copy[k], value);
			const int written = snprintf(with + used, sizeof with - used, "%sparameter %s = %s%s", joint,
			                             doc->parameter_names[k], value, k == last ? ")" : "");
			used += written > 0 ? (size_t)written : 0;
		}
		free(copy);
		return sm_error_set(err, local.status, "%s%s", local.message, with);
	}
	expansion_free(doc->current);
	doc->current = ex;
	free(doc->parameter_values);
	doc->parameter_values = copy;
	return SM_OK;
}

sm_status sm_document_set_parameter(sm_document* doc, int32_t index, double value, sm_error* err)
{
	sm_error_clear(err);
	if (doc == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_set_parameter: no document");
	if (index < 0 || index >= doc->parameter_count)
		return sm_error_set(err, SM_ERROR_NOT_FOUND, "%s: parameter index %d is out of range (%d parameters)",
		                    doc->source, (int)index, (int)doc->parameter_count);
	if (!isfinite(value))
		return sm_error_set(err, SM_ERROR_NOT_FINITE, "%s: parameters.%s: %g is not finite", doc->source,
		                    doc->parameter_names[index], value);
	if (same_value(value, doc->parameter_values[index]))
		return SM_OK;
	double* values = malloc((size_t)doc->parameter_count * sizeof(double));
	if (values == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", doc->source);
	memcpy(values, doc->parameter_values, (size_t)doc->parameter_count * sizeof(double));
	values[index] = value;
	const sm_status st = sm_document_set_parameters(doc, values, err);
	free(values);
	return st;
}

int32_t sm_document_port_count(const sm_document* doc)
{
	return doc != NULL ? doc->current->port_count : 0;
}

sm_port sm_document_port(const sm_document* doc, int32_t index)
{
	if (doc == NULL || index < 0 || index >= doc->current->port_count) {
		sm_port none = {NULL, -1, SM_PORT_PROBE};
		return none;
	}
	return doc->current->ports[index];
}

int32_t sm_document_structure_count(const sm_document* doc)
{
	return doc != NULL ? doc->current->structure_count : 0;
}

sm_structure_info sm_document_structure(const sm_document* doc, int32_t index)
{
	static const char* const types[] = {"rope", "sheet", "block", "mesh"};
	sm_structure_info info;
	memset(&info, 0, sizeof info);
	if (doc == NULL || index < 0 || index >= doc->current->structure_count)
		return info;
	const document_structure* s = &doc->current->structures[index];
	info.name = s->name;
	info.type = types[s->type];
	info.range = s->range;
	return info;
}

const char* sm_document_structure_file(const sm_document* doc, int32_t index)
{
	if (doc == NULL || index < 0 || (size_t)index >= doc->mesh_file_slots || doc->mesh_files[index] == NULL)
		return NULL;
	const json_t* obj = json_array_get(json_object_get(doc->root, "structures"), (size_t)index);
	return json_string_value(json_object_get(obj, "file"));
}

// The file's tree with each "file" of a mesh replaced by the "vertices" and "triangles" read from
// it: the OBJ file's numbers as they are (its "scale" and "origin" stay, and apply to them the
// same way), each a JSON real, which jansson writes with 17 significant digits (exactly, -0 as
// -0.0); the triangles' indices from 0.
char* sm_document_to_self_contained_json(const sm_document* doc, sm_error* err)
{
	sm_error_clear(err);
	if (doc == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "no document");
		return NULL;
	}
	json_t* root = json_deep_copy(doc->root);
	bool ok = root != NULL;
	json_t* structures = json_object_get(root, "structures");
	for (size_t k = 0; ok && k < doc->mesh_file_slots; k++) {
		const document_mesh_file* f = doc->mesh_files[k];
		if (f == NULL)
			continue;
		json_t* obj = json_array_get(structures, k);
		json_t* vertices = json_array();
		json_t* triangles = json_array();
		ok = vertices != NULL && triangles != NULL;
		for (int32_t v = 0; ok && v < f->mesh.vertex_count; v++) {
			const double* x = f->mesh.vertices + 3 * (size_t)v;
			json_t* vertex = json_pack("[fff]", x[0], x[1], x[2]);
			ok = vertex != NULL && json_array_append_new(vertices, vertex) == 0;
		}
		for (int32_t t = 0; ok && t < f->mesh.triangle_count; t++) {
			const int32_t* c = f->mesh.triangles + 3 * (size_t)t;
			json_t* triangle = json_pack("[III]", (json_int_t)c[0], (json_int_t)c[1], (json_int_t)c[2]);
			ok = triangle != NULL && json_array_append_new(triangles, triangle) == 0;
		}
		ok = ok && json_object_del(obj, "file") == 0 && json_object_set(obj, "vertices", vertices) == 0 &&
		     json_object_set(obj, "triangles", triangles) == 0;
		json_decref(vertices);
		json_decref(triangles);
	}
	char* text = NULL;
	if (ok) {
		// In the C locale, as the file was parsed (jansson writes a real's point as the locale has it).
		const sm_c_locale_scope scope = sm_enter_c_locale();
		text = sm_c_locale_entered(scope) ? json_dumps(root, JSON_REAL_PRECISION(17)) : NULL;
		sm_leave_c_locale(scope);
	}
	json_decref(root);
	if (text == NULL) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory for its self-contained text",
		             doc->source);
		return NULL;
	}
	// jansson allocates with malloc (the library sets no other allocator): the caller frees it.
	return text;
}

int32_t sm_document_port_index(const sm_document* doc, const char* name)
{
	if (doc == NULL || name == NULL)
		return -1;
	return sm_name_index_find(&doc->current->port_names, name, strlen(name));
}

int32_t sm_document_particle_count(const sm_document* doc)
{
	return doc != NULL ? sm_model_particle_count(doc->current->model) : 0;
}

int32_t sm_document_spring_count(const sm_document* doc)
{
	return doc != NULL ? sm_model_spring_count(doc->current->model) : 0;
}

const char* sm_document_particle_name(const sm_document* doc, int32_t particle)
{
	if (doc == NULL || particle < 0 || particle >= sm_model_particle_count(doc->current->model))
		return NULL;
	const int64_t offset = doc->current->name_offset[particle];
	return offset >= 0 ? doc->current->names + offset : NULL;
}

int32_t sm_document_particle_index(const sm_document* doc, const char* name)
{
	return doc != NULL && name != NULL ? lookup_name(doc->current, name) : -1;
}

sm_document_settings sm_document_get_settings(const sm_document* doc)
{
	if (doc == NULL) {
		sm_document_settings s;
		memset(&s, 0, sizeof s);
		s.stop_time = 1.0;
		s.output_interval = 0.01;
		s.solver = sm_default_simulation_def();
		s.particle_variables = true;
		return s;
	}
	return doc->current->settings;
}

// Drops the initial state set with sm_document_set_initial_state. The current expansion's model
// holds that state in place of the file's positions and velocities, which the parameters'
// current values expanded without it give back; only its particles are copied over, so that the
// particle names handed out stay valid. If the expansion fails (out of memory) the state stays.
static sm_status drop_initial_state(sm_document* doc, sm_error* err)
{
	if (doc->initial_position == NULL)
		return SM_OK;
	double* position = doc->initial_position;
	double* velocity = doc->initial_velocity;
	doc->initial_position = NULL;
	doc->initial_velocity = NULL;
	sm_error local = {SM_OK, ""};
	expansion* ex = expand(doc, doc->parameter_values, &local);
	if (ex == NULL) {
		doc->initial_position = position;
		doc->initial_velocity = velocity;
		return sm_error_set(err, local.status, "%s", local.message);
	}
	// The same parameter values: the same particles, in the same order.
	const int32_t n = sm_model_particle_count(ex->model);
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def d;
		sm_model_get_particle(ex->model, i, &d);
		sm_model_set_particle(doc->current->model, i, &d);
	}
	expansion_free(ex);
	free(position);
	free(velocity);
	doc->initial_count = 0;
	return SM_OK;
}

sm_status sm_document_set_initial_state(sm_document* doc, const double* x, const double* v, sm_error* err)
{
	sm_error_clear(err);
	if (doc == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_set_initial_state: no document");
	if (x == NULL && v != NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "sm_document_set_initial_state: velocities without positions");
	if (x == NULL)
		return drop_initial_state(doc, err);
	const int32_t n = sm_model_particle_count(doc->current->model);
	for (size_t k = 0; k < 3 * (size_t)n; k++)
		if (!isfinite(x[k]) || (v != NULL && !isfinite(v[k])))
			return sm_error_set(err, SM_ERROR_NOT_FINITE, "%s: initial state of particle %zu is not finite",
			                    doc->source, k / 3);
	// A spring's length must stay a double, as the loader asks of the file's positions: a saved
	// file with particles further apart would not load, and the model could not run.
	const int32_t m = sm_model_spring_count(doc->current->model);
	for (int32_t s = 0; s < m; s++) {
		sm_spring_def def;
		sm_model_get_spring(doc->current->model, s, &def);
		const double* xa = x + 3 * (size_t)def.a;
		const double* xb = x + 3 * (size_t)def.b;
		const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
		if (!isfinite(sqrt(dx * dx + dy * dy + dz * dz)))
			return sm_error_set(
			    err, SM_ERROR_NOT_FINITE,
			    "%s: initial state: spring %ld: the distance between particles %ld and %ld is too "
			    "large (its square overflows: particles joined by springs must be less than "
			    "1.3e154 m apart)",
			    doc->source, (long)s, (long)def.a, (long)def.b);
	}
	double* position = malloc(3 * (size_t)n * sizeof(double) + 1);
	double* velocity = calloc(3 * (size_t)n + 1, sizeof(double));
	if (position == NULL || velocity == NULL) {
		free(position);
		free(velocity);
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", doc->source);
	}
	memcpy(position, x, 3 * (size_t)n * sizeof(double));
	if (v != NULL)
		memcpy(velocity, v, 3 * (size_t)n * sizeof(double));
	// Positions and velocities replace the model's initial state; rest lengths stay as loaded.
	sm_model* model = doc->current->model;
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def d;
		sm_model_get_particle(model, i, &d);
		memcpy(d.position, position + 3 * (size_t)i, sizeof d.position);
		memcpy(d.velocity, velocity + 3 * (size_t)i, sizeof d.velocity);
		sm_model_set_particle(model, i, &d);
	}
	free(doc->initial_position);
	free(doc->initial_velocity);
	doc->initial_position = position;
	doc->initial_velocity = velocity;
	doc->initial_count = n;
	return SM_OK;
}

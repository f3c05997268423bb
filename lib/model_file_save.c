// Model files: the canonical writer.
//
// The canonical form lists every particle and spring explicitly, one per line, in model order,
// with rest lengths written out and parameter references kept, so that loading it builds the
// same model. Numbers are written with the fewest digits that read back to the same double.
#define _POSIX_C_SOURCE 200809L

#include "model_file_internal.h"

#include "c_locale.h"
#include "model_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

typedef struct text {
	char* data;
	size_t length, capacity;
	bool failed;
	// Per parameter: NAMED once the text names it, with UNTOLD once it names it where the key does
	// not tell the unit (NULL: not tracked).
	uint8_t* named;
} text;

enum { NAMED = 1, UNTOLD = 2 };

static void put(text* t, const char* s, size_t n)
{
	if (t->failed)
		return;
	if (t->length + n + 1 > t->capacity) {
		size_t c = t->capacity > 0 ? t->capacity : 4096;
		while (c < t->length + n + 1)
			c *= 2;
		char* grown = realloc(t->data, c);
		if (grown == NULL) {
			t->failed = true;
			return;
		}
		t->data = grown;
		t->capacity = c;
	}
	memcpy(t->data + t->length, s, n);
	t->length += n;
	t->data[t->length] = '\0';
}

static void puts_(text* t, const char* s)
{
	put(t, s, strlen(s));
}

// x in the shortest text that reads back to exactly x (sm_format_number); -0 as -0.0, since the
// JSON reader takes "-0" for the integer 0 and would drop the sign (a position or velocity of
// -0 then reloads as +0, and the reloaded model prints "0" where the saved one printed "-0").
static void put_number(text* t, double x)
{
	char buffer[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(x, buffer);
	if (strcmp(buffer, "-0") == 0)
		strcpy(buffer, "-0.0");
	puts_(t, buffer);
}

// A JSON string. Names and descriptions hold no control characters but a description's tabs
// (the loader refuses the others), so only quotes, backslashes and control characters need
// escaping; UTF-8 passes through.
static void put_string(text* t, const char* s)
{
	puts_(t, "\"");
	const char* run = s;
	for (; *s != '\0'; s++) {
		const unsigned char c = (unsigned char)*s;
		if (c == '"' || c == '\\' || c < 0x20) {
			put(t, run, (size_t)(s - run));
			char escaped[8];
			if (c == '"' || c == '\\')
				snprintf(escaped, sizeof escaped, "\\%c", c);
			else
				snprintf(escaped, sizeof escaped, "\\u%04x", c);
			puts_(t, escaped);
			run = s + 1;
		}
	}
	put(t, run, (size_t)(s - run));
	puts_(t, "\"");
}

// Whether a key is one of `keys` (NULL-terminated).
static bool key_among(const char* key, const char* const* keys)
{
	for (; *keys != NULL; keys++)
		if (strcmp(key, *keys) == 0)
			return true;
	return false;
}

// Whether a key of the simulation settings takes the name of a choice ("method": "bdf"), not a
// number or the parameter that stands for one.
static bool takes_a_choice(const char* key)
{
	static const char* const keys[] = {"method", "solver", "jacobian", "input_changes", NULL};
	return key_among(key, keys);
}

// Whether a parameter at a key copied from the file takes no unit from the key: "atol" sets the
// tolerances of positions [m] and velocities [m/s], "max_steps" is a count.
static bool tells_no_unit(const char* key)
{
	static const char* const keys[] = {"atol", "max_steps", NULL};
	return key_among(key, keys);
}

// A JSON value copied from the file (gravity, mass damping, simulation and FMU settings, all
// validated and shallow) at `key`, with numbers written like every other number; a string that
// names a parameter counts as naming it, unless it is the value of a key that takes a choice (a
// parameter called "bdf" is not what "method": "bdf" names).
static void put_json(text* t, const sm_document* doc, const json_t* value, const char* key)
{
	if (json_is_number(value)) {
		put_number(t, json_number_value(value));
	} else if (json_is_string(value)) {
		const char* s = json_string_value(value);
		put_string(t, s);
		const int32_t k = takes_a_choice(key) ? -1 : sm_name_index_find(&doc->parameter_index, s, strlen(s));
		if (k >= 0 && t->named != NULL)
			t->named[k] |= (uint8_t)(NAMED | (tells_no_unit(key) ? UNTOLD : 0));
	} else if (json_is_array(value)) {
		puts_(t, "[");
		for (size_t k = 0; k < json_array_size(value); k++) {
			puts_(t, k > 0 ? ", " : "");
			put_json(t, doc, json_array_get(value, k), key);
		}
		puts_(t, "]");
	} else if (json_is_object(value)) {
		const char* item_key;
		json_t* item;
		bool first = true;
		puts_(t, "{");
		json_object_foreach((json_t*)value, item_key, item)
		{
			puts_(t, first ? "" : ", ");
			first = false;
			put_string(t, item_key);
			puts_(t, ": ");
			put_json(t, doc, item, item_key);
		}
		puts_(t, "}");
	} else {
		puts_(t, json_is_true(value) ? "true" : json_is_false(value) ? "false" : "null");
	}
}

// A number, or the parameter it came from, at a key that tells its unit or not (`untold`).
static void put_value_at(text* t, const sm_document* doc, double x, int32_t source, bool untold)
{
	if (source >= 0) {
		put_string(t, doc->parameter_names[source]);
		if (t->named != NULL)
			t->named[source] |= (uint8_t)(NAMED | (untold ? UNTOLD : 0));
	} else {
		put_number(t, x);
	}
}

// A number, or the parameter it came from, at a key that tells its unit.
static void put_value(text* t, const sm_document* doc, double x, int32_t source)
{
	put_value_at(t, doc, x, source, false);
}

static void put_vector(text* t, const sm_document* doc, const double x[3], const int32_t sources[3])
{
	puts_(t, "[");
	for (int c = 0; c < 3; c++) {
		if (c > 0)
			puts_(t, ", ");
		put_value(t, doc, x[c], sources != NULL ? sources[c] : -1);
	}
	puts_(t, "]");
}

static void put_particle_reference(text* t, const sm_document* doc, int32_t particle)
{
	const char* name = sm_document_particle_name(doc, particle);
	if (name != NULL) {
		put_string(t, name);
	} else {
		char buffer[16];
		snprintf(buffer, sizeof buffer, "%d", (int)particle);
		puts_(t, buffer);
	}
}

static void put_particle(text* t, const sm_document* doc, int32_t i)
{
	const expansion* ex = doc->current;
	sm_particle_def def;
	sm_model_get_particle(ex->model, i, &def);
	const particle_source* src = &ex->particle_sources[i];
	// Positions and velocities set with sm_document_set_initial_state replace parameters.
	const bool replaced = doc->initial_position != NULL;
	puts_(t, "    {");
	const char* name = sm_document_particle_name(doc, i);
	if (name != NULL) {
		puts_(t, "\"name\": ");
		put_string(t, name);
		puts_(t, ", ");
	}
	puts_(t, "\"position\": ");
	put_vector(t, doc, def.position, replaced ? NULL : src->position);
	// A velocity of zeros is left out, but not one with a -0, which would reload as +0.
	bool moving = false;
	for (int c = 0; c < 3; c++)
		moving = moving || def.velocity[c] != 0.0 || signbit(def.velocity[c]);
	const bool velocity_parameter =
	    !replaced && (src->velocity[0] >= 0 || src->velocity[1] >= 0 || src->velocity[2] >= 0);
	if (moving || velocity_parameter) {
		puts_(t, ", \"velocity\": ");
		put_vector(t, doc, def.velocity, replaced ? NULL : src->velocity);
	}
	puts_(t, ", \"mass\": ");
	put_value(t, doc, def.mass, src->mass);
	if (def.motion == SM_PARTICLE_FIXED)
		puts_(t, ", \"fixed\": true");
	puts_(t, "}");
}

static void put_spring(text* t, const sm_document* doc, int32_t s)
{
	const expansion* ex = doc->current;
	sm_spring_def def;
	sm_model_get_spring(ex->model, s, &def);
	const spring_source* src = &ex->spring_sources[s];
	puts_(t, "    {\"a\": ");
	put_particle_reference(t, doc, def.a);
	puts_(t, ", \"b\": ");
	put_particle_reference(t, doc, def.b);
	// The loader reads "rest_length": 0 as a zero-length spring; say so only when it is not. A
	// rest length from a parameter keeps the file's "kind" or its absence: without one, the
	// parameter's value chooses the law (it feeds spring kinds), with one it does not.
	if (src->rest_length >= 0 ? src->kind_given : def.kind == SM_SPRING_REST_LENGTH && def.rest_length == 0.0)
		puts_(t, def.kind == SM_SPRING_ZERO_LENGTH ? ", \"kind\": \"zero_length\""
		                                           : ", \"kind\": \"rest_length\"");
	puts_(t, ", \"rest_length\": ");
	put_value(t, doc, def.kind == SM_SPRING_ZERO_LENGTH ? 0.0 : def.rest_length, src->rest_length);
	static const char* const stiffness_keys[3] = {
	    ", \"stiffness\": ", ", \"strain_stiffness\": ", ", \"section_stiffness\": "};
	static const char* const damping_keys[3] = {
	    ", \"damping\": ", ", \"strain_damping\": ", ", \"section_damping\": "};
	// A constant of 0 is the default, left out, unless it comes from a parameter or has a scaling
	// (and a section) of its own to keep; -0, which would reload as +0, is written too.
	const bool stiffness = def.stiffness != 0.0 || signbit(def.stiffness) || src->stiffness >= 0 ||
	                       def.stiffness_scaling != SM_ABSOLUTE;
	const bool damping =
	    def.damping != 0.0 || signbit(def.damping) || src->damping >= 0 || def.damping_scaling != SM_ABSOLUTE;
	// A single spring's section is a width or an area: its per-section constants and its section
	// have no unit the key tells, where a structure's had.
	if (stiffness) {
		puts_(t, stiffness_keys[def.stiffness_scaling]);
		put_value_at(t, doc, def.stiffness, src->stiffness, def.stiffness_scaling == SM_PER_SECTION);
	}
	if (damping) {
		puts_(t, damping_keys[def.damping_scaling]);
		put_value_at(t, doc, def.damping, src->damping, def.damping_scaling == SM_PER_SECTION);
	}
	// A structure's spring gets its section from the grid; saved as one spring, it keeps it.
	if ((stiffness && def.stiffness_scaling == SM_PER_SECTION) ||
	    (damping && def.damping_scaling == SM_PER_SECTION)) {
		puts_(t, ", \"section\": ");
		put_value_at(t, doc, def.section, src->section, true);
	}
	if (isfinite(def.break_strain) || src->break_strain >= 0) {
		puts_(t, ", \"break_strain\": ");
		put_value(t, doc, def.break_strain, src->break_strain);
	}
	puts_(t, "}");
}

static const char* port_kind_name(sm_port_kind kind)
{
	switch (kind) {
	case SM_PORT_FORCE: return "force";
	case SM_PORT_MOTION: return "motion";
	case SM_PORT_PROBE: return "probe";
	}
	return "probe";
}

static void write_body(text* t, const sm_document* doc);

static char* document_text(const sm_document* doc, sm_error* err)
{
	if (doc == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_to_json: no document");
		return NULL;
	}
	text t = {NULL, 0, 0, false, NULL};
	char buffer[64];
	snprintf(buffer, sizeof buffer, "{\n  \"springmass\": %d,\n  \"name\": ", SM_FORMAT_VERSION);
	puts_(&t, buffer);
	put_string(&t, doc->name);
	if (doc->description[0] != '\0') {
		puts_(&t, ",\n  \"description\": ");
		put_string(&t, doc->description);
	}
	// The rest first, to learn which parameters it names: only those are listed. A parameter that
	// fed only what the writer writes out as numbers (a structure's total mass, its geometry, its
	// counts, an initial state replaced by sm_document_set_initial_state) would feed nothing.
	text body = {NULL, 0, 0, false, calloc((size_t)doc->parameter_count + 1, 1)};
	if (body.named == NULL)
		t.failed = true;
	write_body(&body, doc);
	if (doc->parameter_count > 0 && body.named != NULL) {
		bool any = false;
		for (int32_t k = 0; k < doc->parameter_count; k++) {
			if (!body.named[k])
				continue;
			puts_(&t, any ? ", " : ",\n  \"parameters\": {");
			any = true;
			put_string(&t, doc->parameter_names[k]);
			puts_(&t, ": ");
			put_number(&t, doc->parameter_values[k]);
		}
		if (any)
			puts_(&t, "}");
		// The units the text would lose: a parameter it names where the key does not tell the unit
		// (a single spring's per-section constant, its section is a width or an area) has none
		// when loaded, unless "parameter_units" gives it the one it has here (from a structure's
		// per-section constant, or from the file's own "parameter_units").
		any = false;
		for (int32_t k = 0; k < doc->parameter_count; k++) {
			const char* unit = sm_document_parameter_unit(doc, k);
			if (!(body.named[k] & UNTOLD) || unit[0] == '\0')
				continue;
			puts_(&t, any ? ", " : ",\n  \"parameter_units\": {");
			any = true;
			put_string(&t, doc->parameter_names[k]);
			puts_(&t, ": ");
			put_string(&t, unit);
		}
		if (any)
			puts_(&t, "}");
	}
	if (body.data != NULL)
		puts_(&t, body.data);
	t.failed = t.failed || body.failed;
	free(body.data);
	free(body.named);
	if (t.failed) {
		free(t.data);
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory while writing the model", doc->source);
		return NULL;
	}
	return t.data;
}

// Everything after the name, description and parameters.
static void write_body(text* t, const sm_document* doc)
{
	const expansion* ex = doc->current;
	const sm_model_def def = sm_model_get_def(ex->model);
	// Gravity and mass damping as the file gave them (they may name parameters).
	puts_(t, ",\n  \"gravity\": ");
	const json_t* gravity = json_object_get(doc->root, "gravity");
	if (gravity != NULL)
		put_json(t, doc, gravity, "gravity");
	else
		put_vector(t, doc, def.gravity, NULL);
	puts_(t, ",\n  \"mass_damping\": ");
	const json_t* mass_damping = json_object_get(doc->root, "mass_damping");
	if (mass_damping != NULL)
		put_json(t, doc, mass_damping, "mass_damping");
	else
		put_number(t, def.mass_damping);

	const int32_t n = sm_model_particle_count(ex->model), m = sm_model_spring_count(ex->model);
	puts_(t, ",\n  \"particles\": [\n");
	for (int32_t i = 0; i < n && !t->failed; i++) {
		put_particle(t, doc, i);
		puts_(t, i + 1 < n ? ",\n" : "\n");
	}
	puts_(t, "  ]");
	if (m > 0) {
		puts_(t, ",\n  \"springs\": [\n");
		for (int32_t s = 0; s < m && !t->failed; s++) {
			put_spring(t, doc, s);
			puts_(t, s + 1 < m ? ",\n" : "\n");
		}
		puts_(t, "  ]");
	}
	if (ex->load_count > 0) {
		puts_(t, ",\n  \"loads\": [\n");
		for (int32_t k = 0; k < ex->load_count; k++) {
			puts_(t, "    {\"particle\": ");
			put_particle_reference(t, doc, ex->loads[k].particle);
			puts_(t, ", \"force\": ");
			put_vector(t, doc, ex->loads[k].force, ex->loads[k].source);
			puts_(t, k + 1 < ex->load_count ? "},\n" : "}\n");
		}
		puts_(t, "  ]");
	}
	if (ex->port_count > 0) {
		puts_(t, ",\n  \"ports\": [\n");
		for (int32_t k = 0; k < ex->port_count; k++) {
			puts_(t, "    {\"name\": ");
			put_string(t, ex->ports[k].name);
			puts_(t, ", \"particle\": ");
			put_particle_reference(t, doc, ex->ports[k].particle);
			puts_(t, ", \"kind\": \"");
			puts_(t, port_kind_name(ex->ports[k].kind));
			puts_(t, k + 1 < ex->port_count ? "\"},\n" : "\"}\n");
		}
		puts_(t, "  ]");
	}
	static const char* const copied[] = {"simulation", "fmu"};
	for (int k = 0; k < 2; k++) {
		const json_t* value = json_object_get(doc->root, copied[k]);
		if (value == NULL)
			continue;
		puts_(t, ",\n  \"");
		puts_(t, copied[k]);
		puts_(t, "\": ");
		put_json(t, doc, value, copied[k]);
	}
	puts_(t, "\n}\n");
}

// The text is written in the C locale (c_locale.h): under a decimal comma (de_DE) printf wrote a
// gravity of 9.81 m/s^2 as "9,81", which is not JSON.
char* sm_document_to_json(const sm_document* doc, sm_error* err)
{
	sm_error_clear(err);
	const sm_c_locale_scope scope = sm_enter_c_locale();
	if (!sm_c_locale_entered(scope)) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "sm_document_to_json: out of memory for the C locale");
		return NULL;
	}
	char* text = document_text(doc, err);
	sm_leave_c_locale(scope);
	return text;
}

// Opens for writing a new file beside path, named .springmass-<pid>-<n>.partial in its folder
// with n from the clock (another name while one of that name exists: O_EXCL; short, so that a
// file whose name is as long as the file system allows has one beside it too), with the
// permissions of the file it will replace, or 0666 less the umask as fopen creates one. Its name
// goes to *temporary (malloc'ed).
static FILE* open_beside(const char* path, const struct stat* replaced, char** temporary)
{
	const char* slash = strrchr(path, '/');
	const int folder = slash != NULL ? (int)(slash - path) + 1 : 0;
	const size_t capacity = (size_t)folder + 64;
	*temporary = malloc(capacity);
	if (*temporary == NULL)
		return NULL;
	struct timespec now;
	clock_gettime(CLOCK_REALTIME, &now);
	int fd = -1;
	for (long n = now.tv_nsec; fd < 0 && n < now.tv_nsec + 100; n++) {
		snprintf(*temporary, capacity, "%.*s.springmass-%ld-%ld.partial", folder, path, (long)getpid(), n);
		fd = open(*temporary, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd < 0 && errno != EEXIST)
			break;
	}
	FILE* f =
	    fd >= 0 && (replaced == NULL || fchmod(fd, replaced->st_mode & 07777) == 0) ? fdopen(fd, "wb") : NULL;
	if (f == NULL) {
		const int code = errno;
		if (fd >= 0) {
			close(fd);
			unlink(*temporary);
		}
		free(*temporary);
		*temporary = NULL;
		errno = code;
	}
	return f;
}

// The file is written whole or not at all: beside the one it replaces, then renamed over it, so
// that a failed write (a full disk) leaves an earlier file as it was. A path that holds no
// regular file (a link, a device), or whose folder takes no new files, is written directly, as
// fopen would.
sm_status sm_document_save(const sm_document* doc, const char* path, sm_error* err)
{
	sm_error_clear(err);
	if (doc == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_save: no document");
	if (path == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "sm_document_save: no file name");
	char* data = sm_document_to_json(doc, err);
	if (data == NULL)
		return err != NULL ? err->status : SM_ERROR_OUT_OF_MEMORY;
	struct stat st;
	const bool exists = lstat(path, &st) == 0;
	const bool regular = !exists || S_ISREG(st.st_mode);  // a file there, or none yet
	char* temporary = NULL;
	FILE* f = regular ? open_beside(path, exists ? &st : NULL, &temporary) : NULL;
	if (f == NULL && (!regular || errno == EACCES || errno == EPERM || errno == EROFS))
		f = fopen(path, "wb");
	if (f == NULL) {
		const int code = errno;
		free(data);
		return sm_error_set(err, SM_ERROR_FILE, "%s: cannot write: %s", path, strerror(code));
	}
	const size_t length = strlen(data);
	errno = 0;
	const bool written = fwrite(data, 1, length, f) == length;
	const int write_code = errno;
	errno = 0;
	const bool closed = fclose(f) == 0;
	int code = !written && write_code != 0 ? write_code : errno;
	free(data);
	bool moved = true;
	if (temporary != NULL) {
		errno = 0;
		moved = written && closed && rename(temporary, path) == 0;
		if (!moved) {
			code = code != 0 ? code : errno;
			unlink(temporary);
		}
		free(temporary);
	}
	if (!written || !closed || !moved)
		return sm_error_set(err, SM_ERROR_FILE, "%s: cannot write: %s", path,
		                    code != 0 ? strerror(code) : "write error");
	return SM_OK;
}

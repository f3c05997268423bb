// Model files: parsing with jansson, validation and evaluation into a model (the format is
// documented in docs/model-format.md).
//
// Loading parses the text into a JSON tree, reads the parameters, then evaluates the tree
// ("expands" it) into a model, the particles' names, the ports and the settings. Every value is
// checked where it is read, so a message can name its path in the document
// (`springs[3].b: no particle named "bobb"`), the value and the rule. Unknown keys are errors.
// Every failure frees what was made so far; nothing is left half-built. The parts of the reader
// are listed in model_file_parser.h.
#define _POSIX_C_SOURCE 200809L  // open, fstat, read

#include "c_locale.h"
#include "model_file_parser.h"
#include "model_file_text.h"

#include "model_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

// Largest model file read from disk [bytes].
#define MAX_FILE_BYTES ((long)1 << 30)

// ---------------------------------------------------------------------------------------------
// Settings.
// ---------------------------------------------------------------------------------------------

static bool read_choice(parser* p, const json_t* obj, const char* path, const char* key,
                        const char* const* names, int count, int* out)
{
	const json_t* value = json_object_get(obj, key);
	if (value == NULL)
		return true;
	char sub[PATH_CAPACITY];
	sm_parser_child_key(sub, path, key);
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
	return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be one of %s", list);
}

static bool read_settings(parser* p, const json_t* simulation, const json_t* fmu)
{
	static const char* const keys[] = {"stop_time",
	                                   "output_interval",
	                                   "rtol",
	                                   "atol",
	                                   "atol_position",
	                                   "atol_velocity",
	                                   "method",
	                                   "solver",
	                                   "jacobian",
	                                   "max_step",
	                                   "max_steps",
	                                   "input_changes",
	                                   "stability_limit_detection",
	                                   NULL};
	static const char* const fmu_keys[] = {"particle_variables", NULL};
	sm_document_settings* s = &p->ex->settings;
	s->stop_time = 1.0;
	s->output_interval = 0.01;
	s->solver = sm_default_simulation_def();
	s->particle_variables = true;
	if (simulation != NULL) {
		const char* path = "simulation";
		if (!sm_parser_expect_object(p, simulation, path) || !sm_parser_check_keys(p, simulation, path, keys))
			return false;
		sm_simulation_def* d = &s->solver;
		double atol = -1.0;
		if (!sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "stop_time", POSITIVE, &s->stop_time,
		                          NULL) ||
		    !sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "output_interval", POSITIVE,
		                          &s->output_interval, NULL) ||
		    !sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "rtol", FRACTION,
		                          &d->relative_tolerance, NULL) ||
		    !sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "atol", TOLERANCE, &atol, NULL) ||
		    !sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "max_step", STEP_CAP, &d->max_step,
		                          NULL))
			return false;
		if (atol > 0.0)
			d->absolute_tolerance_position = d->absolute_tolerance_velocity = atol;
		if (!sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "atol_position", TOLERANCE,
		                          &d->absolute_tolerance_position, NULL) ||
		    !sm_parser_read_field(p, FEEDS_SETTINGS, simulation, path, "atol_velocity", TOLERANCE,
		                          &d->absolute_tolerance_velocity, NULL))
			return false;
		if (json_object_get(simulation, "max_steps") != NULL) {
			int64_t steps;
			if (!sm_parser_read_count(p, FEEDS_SETTINGS, json_object_get(simulation, "max_steps"),
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
		const char* const input_changes[] = {sm_input_changes_name(true), sm_input_changes_name(false)};
		int method = (int)d->method, jacobian = (int)d->jacobian, solver = (int)d->solver;
		int restart = d->restart_on_input_change ? 0 : 1;
		if (!read_choice(p, simulation, path, "method", methods, 2, &method) ||
		    !read_choice(p, simulation, path, "jacobian", jacobians, 2, &jacobian) ||
		    !read_choice(p, simulation, path, "solver", solvers, SM_SOLVER_COUNT, &solver) ||
		    !read_choice(p, simulation, path, "input_changes", input_changes, 2, &restart))
			return false;
		if (!sm_parser_read_bool(p, simulation, path, "stability_limit_detection",
		                         &d->stability_limit_detection))
			return false;
		d->restart_on_input_change = restart == 0;
		d->method = (sm_method)method;
		d->jacobian = (sm_jacobian_variant)jacobian;
		d->solver = (sm_linear_solver)solver;
	}
	if (fmu != NULL) {
		if (!sm_parser_expect_object(p, fmu, "fmu") || !sm_parser_check_keys(p, fmu, "fmu", fmu_keys) ||
		    !sm_parser_read_bool(p, fmu, "fmu", "particle_variables", &s->particle_variables))
			return false;
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Evaluation of the whole document.
// ---------------------------------------------------------------------------------------------

// The path of a parameter's name as a key of `object` ("parameters", "parameter_units"): the
// name escaped as in the messages about it, and cut at a character before the 50 bytes
// sm_parser_child_key keeps of it.
static void parameter_key_path(char path[PATH_CAPACITY], const char* object, const char* name)
{
	char escaped[50];
	if (!sm_text_escape(escaped, sizeof escaped - 4, name))
		strcat(escaped, "...");
	sm_parser_child_key(path, object, escaped);
}

// Evaluates the document's tree with the given parameter values into a new expansion.
expansion* sm_document_expand(const sm_document* doc, const double* parameter_values, sm_error* err)
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
	sm_name_index_init(&p.ex->particle_names, sm_parser_particle_name, p.ex);
	sm_name_index_init(&p.ex->structure_names, sm_parser_structure_name, p.ex);
	sm_name_index_init(&p.ex->port_names, sm_parser_port_name, p.ex);
	const json_t* root = doc->root;
	sm_model_def def = sm_default_model_def();
	int32_t gravity_source[3];
	bool ok = sm_parser_read_vector(&p, FEEDS_CONSTANTS, root, "", "gravity", ANY_FINITE, def.gravity,
	                                gravity_source) &&
	          sm_parser_read_field(&p, FEEDS_CONSTANTS, root, "", "mass_damping", NON_NEGATIVE,
	                               &def.mass_damping, &p.ex->mass_damping_source);
	memcpy(p.ex->gravity_source, gravity_source, sizeof gravity_source);
	if (ok) {
		sm_error model_err;
		p.ex->model = sm_model_create(&def, &model_err);
		if (p.ex->model == NULL)
			ok = sm_parser_fail(&p, model_err.status, "", "%s", model_err.message);
	}
	ok = ok && sm_parser_read_particles(&p, json_object_get(root, "particles")) &&
	     sm_parser_read_structures(&p, json_object_get(root, "structures")) &&
	     sm_parser_read_springs(&p, json_object_get(root, "springs")) &&
	     sm_parser_read_fixed(&p, json_object_get(root, "fixed")) &&
	     sm_parser_read_loads(&p, json_object_get(root, "loads")) &&
	     sm_parser_read_ports(&p, json_object_get(root, "ports")) &&
	     read_settings(&p, json_object_get(root, "simulation"), json_object_get(root, "fmu"));
	// A unit "parameter_units" gives is the parameter's, where the values naming it agreed with it
	// (sm_parser_read_number): an index has none.
	for (int32_t k = 0; ok && k < doc->parameter_count; k++) {
		const char* declared = sm_parser_declared_unit(&p, k);
		if (declared == NULL)
			continue;
		if (p.ex->parameter_uses[k] & FEEDS_REFERENCES) {
			char path[PATH_CAPACITY], text[TEXT_QUOTED_CAPACITY];
			parameter_key_path(path, "parameter_units", doc->parameter_names[k]);
			ok = sm_parser_fail(&p, SM_ERROR_SCHEMA, path,
			                    "parameter %s stands for an index of a structure reference, which has no "
			                    "unit, not %s",
			                    sm_text_quoted(text, doc->parameter_names[k]), declared);
		}
		p.ex->parameter_units[k] = declared;
	}
	if (ok && sm_model_particle_count(p.ex->model) == 0)
		ok = sm_parser_fail(&p, SM_ERROR_SCHEMA, "",
		                    "the model has no particles (give \"particles\" or \"structures\")");
	if (ok && doc->initial_position != NULL) {
		sm_model* model = p.ex->model;
		const int32_t n = sm_model_particle_count(model);
		if (n != doc->initial_count)
			ok = sm_parser_fail(&p, SM_ERROR_TOPOLOGY, "",
			                    "the model now has %d particles but its initial state was set for %d", (int)n,
			                    (int)doc->initial_count);
		for (int32_t i = 0; ok && i < n; i++) {
			sm_particle_def d;
			sm_model_get_particle(model, i, &d);
			memcpy(d.position, doc->initial_position + 3 * (size_t)i, sizeof d.position);
			memcpy(d.velocity, doc->initial_velocity + 3 * (size_t)i, sizeof d.velocity);
			if (sm_model_set_particle(model, i, &d) != SM_OK)
				ok = sm_parser_fail(&p, SM_ERROR_NOT_FINITE, "", "initial state: %s",
				                    sm_model_last_error(model));
		}
	}
	if (!ok) {
		sm_expansion_free(p.ex);
		return NULL;
	}
	return p.ex;
}

// "parameter_units": the units of parameters whose keys do not tell them (a single spring's
// per-section constant: its section is a width or an area), each a unit a key can give; a saved
// file keeps with it the units a structure gave its per-section constants. sm_parser_read_number
// checks that every value naming the parameter whose key tells a unit is in the one given.
static bool read_parameter_units(parser* p, const json_t* units)
{
	static const char* const known[] = {"kg",   "N",     "m",    "m/s", "1", "N/m",  "N.s/m", "N.s",
	                                    "kg/m", "kg/m2", "m/s2", "1/s", "s", "N/m2", "N.s/m2"};
	if (units == NULL)
		return true;
	if (!sm_parser_expect_object(p, units, "parameter_units"))
		return false;
	sm_document* doc = (sm_document*)p->doc;
	doc->parameter_declared_units =
	    calloc(doc->parameter_count > 0 ? (size_t)doc->parameter_count : 1, sizeof(const char*));
	if (doc->parameter_declared_units == NULL)
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "parameter_units", "out of memory");
	const char* key;
	json_t* value;
	json_object_foreach((json_t*)units, key, value)
	{
		char path[PATH_CAPACITY], text[TEXT_QUOTED_CAPACITY];
		parameter_key_path(path, "parameter_units", key);
		const int32_t k = sm_document_find_parameter(doc, key);
		if (k < 0)
			return sm_parser_fail(p, SM_ERROR_NOT_FOUND, path,
			                      "no parameter named %s (\"parameter_units\" gives units to the "
			                      "\"parameters\")",
			                      sm_text_quoted(text, key));
		const char* unit = json_is_string(value) ? json_string_value(value) : NULL;
		for (size_t u = 0; unit != NULL && u < sizeof known / sizeof known[0]; u++)
			if (strcmp(known[u], unit) == 0)
				doc->parameter_declared_units[k] = known[u];
		if (doc->parameter_declared_units[k] == NULL) {
			char list[160] = "";
			size_t used = 0;
			for (size_t u = 0; u < sizeof known / sizeof known[0]; u++)
				used += (size_t)snprintf(list + used, sizeof list - used, "%s\"%s\"", u > 0 ? ", " : "",
				                         known[u]);
			if (unit == NULL)
				return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
				                      "must be the name of a unit, one of %s, not %s", list,
				                      sm_parser_type_name(value));
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s is no unit a value can have: one of %s",
			                      sm_text_quoted(text, unit), list);
		}
	}
	return true;
}

static bool read_header(sm_document* doc, sm_error* err)
{
	static const char* const keys[] = {"springmass",      "name",       "description",  "parameters",
	                                   "parameter_units", "gravity",    "mass_damping", "particles",
	                                   "springs",         "structures", "fixed",        "loads",
	                                   "ports",           "simulation", "fmu",          NULL};
	parser p = {.doc = doc, .err = err};
	const json_t* root = doc->root;
	if (!json_is_object(root))
		return sm_parser_fail(&p, SM_ERROR_SCHEMA, "", "a model file is a JSON object, not %s",
		                      sm_parser_type_name(root));
	if (!sm_parser_check_keys(&p, root, "", keys))
		return false;
	const json_t* version = json_object_get(root, "springmass");
	if (version == NULL)
		return sm_parser_fail(
		    &p, SM_ERROR_SCHEMA, "",
		    "missing \"springmass\": %d (the format version; is this a springmass model file?)",
		    SM_FORMAT_VERSION);
	if (!json_is_integer(version))
		return sm_parser_fail(&p, SM_ERROR_SCHEMA, "springmass",
		                      "format version must be the integer %d, not %s", SM_FORMAT_VERSION,
		                      json_is_string(version) ? "a string (no quotes)"
		                      : json_is_real(version) ? "a real number"
		                                              : "that");
	if (json_integer_value(version) != SM_FORMAT_VERSION)
		return sm_parser_fail(&p, SM_ERROR_SCHEMA, "springmass",
		                      "format version must be %d (this build reads version %d)", SM_FORMAT_VERSION,
		                      SM_FORMAT_VERSION);
	if (!sm_parser_require(&p, root, "", "name") ||
	    !sm_parser_check_name(&p, json_object_get(root, "name"), "name", true, &doc->name))
		return false;
	const json_t* description = json_object_get(root, "description");
	doc->description = "";
	if (description != NULL) {
		if (!json_is_string(description))
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, "description", "must be a string, not %s",
			                      sm_parser_type_name(description));
		doc->description = json_string_value(description);
		int64_t position;
		const int32_t c = sm_text_find_refused(doc->description, sm_text_refused_in_description, &position);
		if (c >= 0 && sm_text_is_line_break(c))
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, "description",
			                      "must be one line: it has a line break, U+%04X, at character %lld",
			                      (unsigned)c, (long long)position);
		if (c >= 0)
			return sm_parser_fail(
			    &p, SM_ERROR_SCHEMA, "description",
			    "has a control character, U+%04X, at character %lld (a tab is the only one allowed)",
			    (unsigned)c, (long long)position);
	}
	const json_t* parameters = json_object_get(root, "parameters");
	if (parameters == NULL)
		return read_parameter_units(&p, json_object_get(root, "parameter_units"));
	if (!sm_parser_expect_object(&p, parameters, "parameters"))
		return false;
	const size_t n = json_object_size(parameters);
	doc->parameter_names = calloc(n > 0 ? n : 1, sizeof(char*));
	doc->parameter_values = calloc(n > 0 ? n : 1, sizeof(double));
	if (doc->parameter_names == NULL || doc->parameter_values == NULL)
		return sm_parser_fail(&p, SM_ERROR_OUT_OF_MEMORY, "parameters", "out of memory");
	const char* key;
	json_t* value;
	json_object_foreach((json_t*)parameters, key, value)
	{
		char path[PATH_CAPACITY];
		parameter_key_path(path, "parameters", key);
		if (!sm_parser_check_name_text(&p, key, strlen(key), path, true))
			return false;
		if (!json_is_number(value))
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, path, "a parameter's value must be a number, not %s",
			                      sm_parser_type_name(value));
		const double v = json_number_value(value);
		if (!isfinite(v))
			return sm_parser_fail(&p, SM_ERROR_NOT_FINITE, path, "%g is not finite", v);
		doc->parameter_names[doc->parameter_count] = key;
		doc->parameter_values[doc->parameter_count] = v;
		int32_t holder;  // the JSON parser refused repeated keys
		if (!sm_name_index_insert(&doc->parameter_index, key, strlen(key), doc->parameter_count, &holder))
			return sm_parser_fail(&p, SM_ERROR_OUT_OF_MEMORY, "parameters", "out of memory");
		doc->parameter_count++;
	}
	return read_parameter_units(&p, json_object_get(root, "parameter_units"));
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

// The opening quote of the string whose closing quote is text[close]: the first '"' before it
// that no backslash escapes (inside a string every '"' is escaped). `close` itself if there is none.
static size_t opening_quote(const char* text, size_t close)
{
	for (size_t open = close; open > 0;) {
		open--;
		size_t backslashes = 0;
		while (backslashes < open && text[open - 1 - backslashes] == '\\')
			backslashes++;
		if (text[open] == '"' && backslashes % 2 == 0)
			return open;
	}
	return close;
}

// The parser quotes the token an error names only up to this many bytes: a longer one it names
// not at all ("duplicate object key", "real number overflow").
#define PARSER_QUOTED_TOKEN_BYTES 20

// Where the token an error names whole begins, as the offset of its first byte; `at` (the bytes the
// parser read, up to the token's last) for any other error. A token the parser quotes whole ("'}'
// expected near '\"name\"'", "invalid token near 'NaN'", a repeated key, a number out of range)
// is reported at its first character, where an editor's cursor should go to mend it; an error
// inside a string (an escape, a control character) stays at the character at fault. A token
// longer than the parser quotes is found in the text, ending at `at`: a string from its opening
// quote, a number or a word back to the white space or punctuation before it; *unquoted then gets
// its length, for the message to quote it (0 otherwise).
static size_t token_start(const json_error_t* error, const char* text, size_t at, size_t* unquoted)
{
	*unquoted = 0;
	const enum json_error_code code = json_error_code(error);
	const char* near = strstr(error->text, " near '");
	const size_t length = strlen(error->text);
	const bool expected = length > 9 && strcmp(error->text + length - 9, " expected") == 0;
	const bool whole = code == json_error_duplicate_key || code == json_error_numeric_overflow ||
	                   (code == json_error_invalid_syntax &&
	                    (strstr(error->text, " expected near '") != NULL ||
	                     strncmp(error->text, "invalid token near '", 20) == 0 ||
	                     strncmp(error->text, "unexpected token near '", 23) == 0 ||
	                     (near == NULL && (expected || strcmp(error->text, "invalid token") == 0 ||
	                                       strcmp(error->text, "unexpected token") == 0))));
	if (!whole || at == 0)
		return at;
	if (near == NULL) {
		size_t start = at;
		if (text[at - 1] == '"')
			start = opening_quote(text, at - 1);
		else
			while (start > 0 && strchr(" \t\r\n{}[],:\"", text[start - 1]) == NULL)
				start--;
		if (at - start <= PARSER_QUOTED_TOKEN_BYTES)
			return at;  // a token the parser would have quoted: not the one the error is on
		*unquoted = at - start;
		return start;
	}
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
	const size_t open = opening_quote(text, at - 1);
	if (open == at - 1)
		return at;
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
// a structure that is no mesh, is left for sm_document_expand() to name.
static bool read_mesh_files(sm_document* doc, const char* folder, sm_error* err)
{
	parser p = {.doc = doc, .err = err};
	const json_t* list = json_object_get(doc->root, "structures");
	if (!json_is_array(list))
		return true;
	const size_t n = json_array_size(list);
	doc->mesh_files = calloc(n > 0 ? n : 1, sizeof *doc->mesh_files);
	if (doc->mesh_files == NULL)
		return sm_parser_fail(&p, SM_ERROR_OUT_OF_MEMORY, "structures", "out of memory");
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
		sm_parser_child_index(path, "structures", k);
		sm_parser_child_key(sub, path, "file");
		if (!json_is_string(file))
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, sub,
			                      "must be a string, the path of an OBJ file, not %s",
			                      sm_parser_type_name(file));
		if (json_object_get(obj, "vertices") != NULL || json_object_get(obj, "triangles") != NULL)
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, path,
			                      "give \"file\" (an OBJ file) or \"vertices\" and \"triangles\", not both");
		const char* name = json_string_value(file);
		if (name[0] == '\0')
			return sm_parser_fail(&p, SM_ERROR_SCHEMA, sub, "must name an OBJ file, not be empty");
		// A relative path is the model file's folder's.
		const size_t folder_bytes = folder != NULL && name[0] != '/' ? strlen(folder) : 0;
		const bool slash = folder_bytes > 0 && folder[folder_bytes - 1] != '/';
		char* joined = malloc(folder_bytes + slash + strlen(name) + 1);
		document_mesh_file* f = calloc(1, sizeof *f);
		if (f == NULL) {
			free(joined);
			return sm_parser_fail(&p, SM_ERROR_OUT_OF_MEMORY, sub, "out of memory");
		}
		doc->mesh_files[k] = f;  // freed with the document, as is its path
		f->path = joined;
		if (joined == NULL || (f->shown = malloc(SM_TEXT_SHOWN_PATH_BYTES + 1)) == NULL)
			return sm_parser_fail(&p, SM_ERROR_OUT_OF_MEMORY, sub, "out of memory");
		if (folder_bytes > 0)
			memcpy(joined, folder, folder_bytes);
		if (slash)
			joined[folder_bytes] = '/';
		strcpy(joined + folder_bytes + slash, name);
		sm_text_shown_path(f->shown, joined);
		char* text = NULL;
		size_t length = 0;
		sm_error file_err = {SM_OK, ""};
		const sm_status read = read_regular_file(joined, f->shown, &text, &length, &file_err);
		if (read != SM_OK)
			return sm_parser_fail(&p, read, sub, "%s", file_err.message);
		int line, column;
		char message[MESH_FILE_MESSAGE_CAPACITY];
		const sm_status st = sm_mesh_file_parse(text, length, doc->max_elements, max_triangles, &f->mesh,
		                                        &line, &column, message);
		free(text);
		if (st != SM_OK && line > 0)
			return sm_parser_fail(&p, st, sub, "%s:%d:%d: %s", f->shown, line, column, message);
		if (st != SM_OK)
			return sm_parser_fail(&p, st, sub, "%s: %s", f->shown, message);
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
	// Messages name the model as they name an OBJ file: escaped, a long path by its end.
	char shown_source[SM_TEXT_SHOWN_PATH_BYTES + 1];
	sm_text_shown_path(shown_source, source_name);
	source_name = shown_source;
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
	sm_name_index_init(&doc->parameter_index, sm_parser_parameter_name, doc);
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
		size_t unquoted = 0;
		const size_t start = before ? at : escape < at ? escape : token_start(&error, text, at, &unquoted);
		sm_text_position(text, length, before ? at + 1 : start < at ? start + 1 : at, &line, &column);
		if (before && ((unsigned char)text[at] & 0xc0) == 0x80)
			column++;
		// A token too long for the parser to quote is quoted here, as a name in a message is: up to
		// QUOTE_TEXT_BYTES, cut at a character with "..." after the quote.
		char message[JSON_ERROR_TEXT_LENGTH + QUOTE_TEXT_BYTES + 16];
		size_t cut = unquoted < QUOTE_TEXT_BYTES ? unquoted : QUOTE_TEXT_BYTES;
		while (cut < unquoted && cut > 0 && ((unsigned char)text[start + cut] & 0xc0) == 0x80)
			cut--;
		if (unquoted > 0)
			snprintf(message, sizeof message, "%s near '%.*s'%s", error.text, (int)cut, text + start,
			         cut < unquoted ? "..." : "");
		else
			snprintf(message, sizeof message, "%s", error.text);
		char shown[6 * sizeof message + 1];
		sm_text_shown(shown, sizeof shown - 1, message);
		if (code == json_error_null_character || code == json_error_null_byte_in_key)
			sm_error_set(err, SM_ERROR_SYNTAX, "%s:%d:%d: strings in a model file may not contain \\u0000",
			             source_name, line, column);
		else
			sm_error_set(err, SM_ERROR_SYNTAX, "%s:%d:%d: %s%s", source_name, line, column, shown,
			             missing_comma(message) ? " (or a ',' before it)" : "");
		sm_document_destroy(doc);
		return NULL;
	}
	if (!read_header(doc, err) || !read_mesh_files(doc, folder, err) ||
	    (doc->current = sm_document_expand(doc, doc->parameter_values, err)) == NULL) {
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
	char shown[SM_TEXT_SHOWN_PATH_BYTES + 1];
	sm_text_shown_path(shown, path);
	if (read_regular_file(path, shown, &text, &length, err) != SM_OK)
		return NULL;
	// The OBJ files a model names are found beside it: in the folder of its path.
	const char* slash = strrchr(path, '/');
	const size_t folder_bytes = slash == NULL ? 0 : slash == path ? 1 : (size_t)(slash - path);
	char* folder = malloc(folder_bytes + 1);
	sm_document* doc = NULL;
	if (folder == NULL)
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "%s: out of memory", shown);
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
	sm_expansion_free(doc->current);
	json_decref(doc->root);
	free(doc->parameter_names);
	free(doc->parameter_declared_units);
	sm_name_index_free(&doc->parameter_index);
	free(doc->parameter_values);
	free(doc->initial_position);
	free(doc->initial_velocity);
	for (size_t k = 0; k < doc->mesh_file_slots; k++) {
		if (doc->mesh_files[k] == NULL)
			continue;
		sm_mesh_file_free(&doc->mesh_files[k]->mesh);
		free(doc->mesh_files[k]->path);
		free(doc->mesh_files[k]->shown);
		free(doc->mesh_files[k]);
	}
	free(doc->mesh_files);
	free(doc->source);
	free(doc);
}

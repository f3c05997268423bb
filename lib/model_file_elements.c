// Model files: the elements read one by one. The expansion's storage (where each particle's and
// spring's values came from, the particles' names), particle references (an index, a name, or
// name[i, j, k] into a structure, with indices that may be expressions of parameters), and the
// lists "particles", "springs", "fixed", "loads" and "ports".
#include "index_expression.h"
#include "model_file_parser.h"
#include "model_file_text.h"

#include "model_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// Expansion storage: per-particle and per-spring sources, particle names.
// ---------------------------------------------------------------------------------------------

void sm_expansion_free(expansion* ex)
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
bool sm_parser_grow_array(void* array, int64_t* capacity, int64_t needed, size_t size, void** grown)
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

// Room for the sources and names of `particles` and `springs` in all.
bool sm_parser_reserve(parser* p, int64_t particles, int64_t springs)
{
	expansion* ex = p->ex;
	int64_t pc = ex->particle_capacity;
	void* spare;
	if (!GROW_ARRAY(ex->particle_sources, &pc, particles, spare))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld particles",
		                      (long long)particles);
	pc = ex->particle_capacity;
	if (!GROW_ARRAY(ex->name_offset, &pc, particles, spare))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld particles",
		                      (long long)particles);
	ex->particle_capacity = pc;
	if (!GROW_ARRAY(ex->spring_sources, &ex->spring_capacity, springs, spare))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "", "out of memory for %lld springs",
		                      (long long)springs);
	return true;
}

// The names of the expansion's particles, structures and ports, and of the document's
// parameters, for their name indexes.
const char* sm_parser_particle_name(const void* owner, int32_t particle)
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
		         sm_text_quoted(text, sm_parser_particle_name(ex, particle)));
	else
		snprintf(buffer, size, "particle %d", (int)particle);
	return buffer;
}

const char* sm_parser_structure_name(const void* owner, int32_t structure)
{
	return ((const expansion*)owner)->structures[structure].name;
}

const char* sm_parser_port_name(const void* owner, int32_t port)
{
	return ((const expansion*)owner)->ports[port].name;
}

const char* sm_parser_parameter_name(const void* owner, int32_t parameter)
{
	return ((const sm_document*)owner)->parameter_names[parameter];
}

int32_t sm_expansion_lookup_name(const expansion* ex, const char* name)
{
	return sm_name_index_find(&ex->particle_names, name, strlen(name));
}

bool sm_parser_name_particle(parser* p, const char* path, int32_t index, const char* format, ...)
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
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "particle name %s would have more than %d bytes",
		                      sm_text_quoted(text, name), MAX_NAME_BYTES);
	const int32_t other = sm_expansion_lookup_name(ex, name);
	if (other >= 0)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "particle name %s is already used by particle %d",
		                      sm_text_quoted(text, name), (int)other);
	const int64_t length = (int64_t)strlen(name) + 1;
	void* spare;
	if (!GROW_ARRAY(ex->names, &ex->names_capacity, ex->names_length + length, spare))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for particle names");
	memcpy(ex->names + ex->names_length, name, (size_t)length);
	ex->name_offset[index] = ex->names_length;
	int32_t holder;
	if (!sm_name_index_insert(&ex->particle_names, name, (size_t)length - 1, index, &holder)) {
		ex->name_offset[index] = -1;
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for particle names");
	}
	ex->names_length += length;
	return true;
}

const document_structure* sm_parser_find_structure(const expansion* ex, const char* name, size_t length)
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
	sm_parser_note_unit(p->ex, k, NULL);
	sm_parser_note_parameter(&named->noted, k);
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
			return sm_parser_fail(p, SM_ERROR_NOT_FOUND, path, "%s: %s", text, why);
		if (status == INDEX_EXPRESSION_NOT_WHOLE)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s: %s", text, why);
		if (status == INDEX_EXPRESSION_INVALID) {
			snprintf(message, sizeof message, "%s: %s", text, why);
			return sm_parser_fail_naming(p, SM_ERROR_SCHEMA, path, message, &named.noted);
		}
		if (status == INDEX_EXPRESSION_SYNTAX && count < 3)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s: %s; %s", text, why, form);
		if (status != INDEX_EXPRESSION_OK || (*end == ']' && end[1] != '\0') || *end == '\0')
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "%s: %s", text, form);
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
		_Static_assert(sizeof forms / sizeof forms[0] == STRUCTURE_TYPE_COUNT,
		               "a form for every structure type");
		return sm_parser_fail(p, SM_ERROR_PARTICLE_INDEX, path, "%s has %d indices: %s", text, count,
		                      forms[s->type]);
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
			sm_parser_note_parameter(&p->noted, named.noted.index[k]);
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
	return sm_parser_fail_naming(p, SM_ERROR_PARTICLE_INDEX, path, message, &named.noted);
}

// A particle reference: an index, a particle's name, or "structure[i, j, k]"
// (resolve_structure_reference).
static bool resolve_particle(parser* p, const json_t* value, const char* path, int32_t* out)
{
	const int32_t n = sm_model_particle_count(p->ex->model);
	if (json_is_integer(value)) {
		const json_int_t i = json_integer_value(value);
		if (i < 0 || i >= n)
			return sm_parser_fail(p, SM_ERROR_PARTICLE_INDEX, path,
			                      "particle index %lld is out of range (the model has %d particle%s)",
			                      (long long)i, (int)n, n == 1 ? "" : "s");
		*out = (int32_t)i;
		return true;
	}
	if (json_is_real(value)) {
		// 3.0 is index 3, as a count may be written 3.0; 2.5 is no index.
		const double v = json_real_value(value);
		char text[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(v, text);
		if (!(v == floor(v)))
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "a particle index must be a whole number, not %s",
			                      text);
		if (!(v >= 0.0 && v < (double)n))
			return sm_parser_fail(p, SM_ERROR_PARTICLE_INDEX, path,
			                      "particle index %s is out of range (the model has %d particle%s)", text,
			                      (int)n, n == 1 ? "" : "s");
		*out = (int32_t)v;
		return true;
	}
	if (!json_is_string(value))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "must be a particle name or index, not %s",
		                      sm_parser_type_name(value));
	const char* name = json_string_value(value);
	char text[TEXT_QUOTED_CAPACITY];
	sm_text_quoted(text, name);
	const int32_t found = sm_expansion_lookup_name(p->ex, name);
	if (found >= 0) {
		*out = found;
		return true;
	}
	// "structure[...]": indices with other spacing than the generated names, or expressions.
	const char* open = strchr(name, '[');
	const size_t length = strlen(name);
	if (open != NULL && length > 0 && name[length - 1] == ']') {
		const document_structure* s = sm_parser_find_structure(p->ex, name, (size_t)(open - name));
		if (s != NULL)
			return resolve_structure_reference(p, s, open, text, path, out);
	}
	// A parameter's name is no particle reference: an index is written as a number, and only a
	// structure reference's indices take parameters.
	if (sm_document_find_parameter(p->doc, name) >= 0)
		return sm_parser_fail(
		    p, SM_ERROR_NOT_FOUND, path,
		    "no particle named %s (%s is a parameter, and a parameter cannot stand for a particle's "
		    "index: name the particle, or refer to a structure's particle as name[i] with i an "
		    "expression of parameters)",
		    text, text);
	return sm_parser_fail(p, SM_ERROR_NOT_FOUND, path, "no particle named %s", text);
}

// ---------------------------------------------------------------------------------------------
// Particles.
// ---------------------------------------------------------------------------------------------

bool sm_parser_read_particles(parser* p, const json_t* list)
{
	static const char* const keys[] = {"name", "position", "velocity", "mass", "fixed", NULL};
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "particles", "must be an array of particles, not %s",
		                      sm_parser_type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "particles", "%zu particles exceed the limit of %lld", n,
		                      (long long)p->doc->max_elements);
	if (!sm_parser_reserve(p, (int64_t)n, 0))
		return false;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY];
		sm_parser_child_index(path, "particles", k);
		const json_t* obj = json_array_get(list, k);
		if (!sm_parser_expect_object(p, obj, path) || !sm_parser_check_keys(p, obj, path, keys))
			return false;
		sm_particle_def def = sm_default_particle_def();
		particle_source src;
		bool fixed = false;
		if (!sm_parser_require(p, obj, path, "position") ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "position", ANY_FINITE, def.position,
		                           src.position) ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "velocity", ANY_FINITE, def.velocity,
		                           src.velocity) ||
		    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "mass", MASS, &def.mass, &src.mass) ||
		    !sm_parser_read_bool(p, obj, path, "fixed", &fixed))
			return false;
		def.motion = fixed ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
		int32_t index;
		if (sm_model_add_particle(p->ex->model, &def, &index) != SM_OK)
			return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "%s", sm_model_last_error(p->ex->model));
		p->ex->particle_sources[index] = src;
		p->ex->name_offset[index] = -1;
		const json_t* name = json_object_get(obj, "name");
		if (name != NULL) {
			char sub[PATH_CAPACITY];
			sm_parser_child_key(sub, path, "name");
			const char* s;
			if (!sm_parser_check_name(p, name, sub, false, &s) ||
			    !sm_parser_name_particle(p, sub, index, "%s", s))
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
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "give one of \"%s\", \"%s\" and \"%s\", not more",
		                      constant_key(constant, SM_ABSOLUTE), constant_key(constant, SM_PER_STRAIN),
		                      constant_key(constant, SM_PER_SECTION));
	return true;
}

// Stiffness and damping, each absolute ("stiffness" [N/m], "damping" [N s/m]), per unit strain
// ("strain_stiffness" [N], "strain_damping" [N s]) or per unit strain and section
// ("section_stiffness", "section_damping": sm_scaling's SM_PER_SECTION), and "break_strain".
bool sm_parser_read_constants(parser* p, const json_t* obj, const char* path, sm_spring_material* m,
                              spring_source* src)
{
	if (!read_scaling(p, obj, path, "stiffness", &m->stiffness_scaling) ||
	    !read_scaling(p, obj, path, "damping", &m->damping_scaling))
		return false;
	m->stiffness = 0.0;
	m->damping = 0.0;
	m->break_strain = INFINITY;
	if (!sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, constant_key("stiffness", m->stiffness_scaling),
	                          NON_NEGATIVE, &m->stiffness, &src->stiffness) ||
	    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, constant_key("damping", m->damping_scaling),
	                          NON_NEGATIVE, &m->damping, &src->damping))
		return false;
	const json_t* brk = json_object_get(obj, "break_strain");
	src->break_strain = -1;
	if (brk != NULL && !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "break_strain", POSITIVE,
	                                         &m->break_strain, &src->break_strain))
		return false;
	return true;
}

bool sm_parser_read_springs(parser* p, const json_t* list)
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
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "springs", "must be an array of springs, not %s",
		                      sm_parser_type_name(list));
	const size_t n = json_array_size(list);
	sm_model* model = p->ex->model;
	if ((int64_t)n + sm_model_spring_count(model) > p->doc->max_elements)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "springs", "%zu more springs exceed the limit of %lld", n,
		                      (long long)p->doc->max_elements);
	if (!sm_parser_reserve(p, sm_model_particle_count(model), sm_model_spring_count(model) + (int64_t)n))
		return false;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		sm_parser_child_index(path, "springs", k);
		const json_t* obj = json_array_get(list, k);
		if (!sm_parser_expect_object(p, obj, path) || !sm_parser_check_keys(p, obj, path, keys) ||
		    !sm_parser_require(p, obj, path, "a") || !sm_parser_require(p, obj, path, "b"))
			return false;
		sm_spring_def def = sm_default_spring_def();
		sm_parser_forget_parameters(p);
		sm_parser_child_key(sub, path, "a");
		if (!resolve_particle(p, json_object_get(obj, "a"), sub, &def.a))
			return false;
		sm_parser_child_key(sub, path, "b");
		if (!resolve_particle(p, json_object_get(obj, "b"), sub, &def.b))
			return false;
		if (def.a == def.b) {
			char message[SM_ERROR_MESSAGE_CAPACITY];
			char which[TEXT_QUOTED_CAPACITY + 32];
			snprintf(message, sizeof message, "connects %s to itself (a and b are the same particle)",
			         describe_particle(p->ex, def.a, which, sizeof which));
			return sm_parser_fail_naming_parameters(p, SM_ERROR_SELF_SPRING, path, message);
		}
		spring_source src = {-1, -1, -1, -1, -1, false};
		sm_spring_material m;
		if (!sm_parser_read_constants(p, obj, path, &m, &src))
			return false;
		// A spring's own section: per-section constants of a single spring need it.
		const bool per_section = m.stiffness_scaling == SM_PER_SECTION || m.damping_scaling == SM_PER_SECTION;
		if (json_object_get(obj, "section") != NULL) {
			if (!per_section)
				return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
				                      "\"section\" goes with \"section_stiffness\" or \"section_damping\"");
			if (!sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "section", POSITIVE, &def.section,
			                          &src.section))
				return false;
		} else if (per_section) {
			return sm_parser_fail(
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
		if (rest != NULL && !sm_parser_read_field(p, rest_use, obj, path, "rest_length", NON_NEGATIVE,
		                                          &def.rest_length, &src.rest_length))
			return false;
		def.kind = rest != NULL && def.rest_length == 0.0 ? SM_SPRING_ZERO_LENGTH : SM_SPRING_REST_LENGTH;
		if (kind != NULL) {
			sm_parser_child_key(sub, path, "kind");
			const char* s = json_is_string(kind) ? json_string_value(kind) : "";
			if (strcmp(s, "zero_length") == 0)
				def.kind = SM_SPRING_ZERO_LENGTH;
			else if (strcmp(s, "rest_length") == 0)
				def.kind = SM_SPRING_REST_LENGTH;
			else
				return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be \"rest_length\" or \"zero_length\"");
			char text[DESCRIPTION_CAPACITY];
			if (def.kind == SM_SPRING_ZERO_LENGTH && rest != NULL && def.rest_length != 0.0)
				return sm_parser_fail(
				    p, SM_ERROR_SCHEMA, path, "a zero-length spring cannot have rest_length %s",
				    sm_parser_describe(p, text, sizeof text, def.rest_length, src.rest_length));
		}
		if (def.kind == SM_SPRING_ZERO_LENGTH)
			def.rest_length = 0.0;
		int32_t index;
		const sm_status st = sm_model_add_spring(model, &def, &index);
		if (st != SM_OK) {
			// The model numbers springs from structures first; the path already names this one.
			const char* message = sm_model_last_error(model);
			const char* rule = strncmp(message, "spring ", 7) == 0 ? strstr(message, ": ") : NULL;
			return sm_parser_fail_naming_parameters(p, st, path, rule != NULL ? rule + 2 : message);
		}
		p->ex->spring_sources[index] = src;
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Fixed particles, loads, ports.
// ---------------------------------------------------------------------------------------------

// Most boxes "fixed" may hold. Each box tests every particle, so that their work is at most this
// many times the model's size: a short file of many boxes on a large structure would otherwise
// take minutes (40 000 boxes on a rope of a million particles: 4e10 tests).
#define MAX_FIXED_BOXES 256

// "fixed": [reference, ..., {"min": [x, y, z], "max": [x, y, z]}, ...]; marks the particles
// in fix[].
static bool read_fixed_to(parser* p, const json_t* list, bool* fix)
{
	static const char* const box_keys[] = {"min", "max", NULL};
	const sm_model* model = p->ex->model;
	int boxes = 0;
	for (size_t k = 0; k < json_array_size(list); k++) {
		char path[PATH_CAPACITY];
		sm_parser_child_index(path, "fixed", k);
		const json_t* item = json_array_get(list, k);
		if (json_is_object(item)) {
			if (++boxes > MAX_FIXED_BOXES)
				return sm_parser_fail(
				    p, SM_ERROR_SCHEMA, path,
				    "more than %d boxes (each box tests every particle): name the particles "
				    "by reference",
				    MAX_FIXED_BOXES);
			double lo[3], hi[3];
			int32_t lo_sources[3], hi_sources[3];
			if (!sm_parser_check_keys(p, item, path, box_keys) || !sm_parser_require(p, item, path, "min") ||
			    !sm_parser_require(p, item, path, "max") ||
			    !sm_parser_read_vector(p, FEEDS_MOTION, item, path, "min", ANY_FINITE, lo, lo_sources) ||
			    !sm_parser_read_vector(p, FEEDS_MOTION, item, path, "max", ANY_FINITE, hi, hi_sources))
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
				return sm_parser_fail(p, SM_ERROR_SCHEMA, path, "the box from %s to %s contains no particle",
				                      sm_parser_describe_vector(p, from, sizeof from, lo, lo_sources),
				                      sm_parser_describe_vector(p, to, sizeof to, hi, hi_sources));
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
bool sm_parser_read_loads(parser* p, const json_t* list)
{
	static const char* const keys[] = {"particle", "force", NULL};
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "loads", "must be an array of loads, not %s",
		                      sm_parser_type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "loads", "too many loads (%zu)", n);
	p->ex->loads = calloc(n > 0 ? n : 1, sizeof(document_load));
	if (p->ex->loads == NULL)
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "loads", "out of memory");
	sm_model* model = p->ex->model;
	for (size_t k = 0; k < n; k++) {
		char path[PATH_CAPACITY], sub[PATH_CAPACITY];
		sm_parser_child_index(path, "loads", k);
		const json_t* obj = json_array_get(list, k);
		document_load* load = &p->ex->loads[k];
		sm_parser_child_key(sub, path, "particle");
		sm_parser_forget_parameters(p);
		if (!sm_parser_expect_object(p, obj, path) || !sm_parser_check_keys(p, obj, path, keys) ||
		    !sm_parser_require(p, obj, path, "particle") || !sm_parser_require(p, obj, path, "force") ||
		    !resolve_particle(p, json_object_get(obj, "particle"), sub, &load->particle) ||
		    !sm_parser_read_vector(p, FEEDS_CONSTANTS, obj, path, "force", ANY_FINITE, load->force,
		                           load->source))
			return false;
		p->ex->load_count++;
		sm_particle_def def;
		sm_model_get_particle(model, load->particle, &def);
		for (int c = 0; c < 3; c++)
			def.load[c] += load->force[c];
		// Loads on one particle whose sum is beyond a double are refused; the model names the particle.
		if (sm_model_set_particle(model, load->particle, &def) != SM_OK)
			return sm_parser_fail_naming_parameters(p, SM_ERROR_NOT_FINITE, path, sm_model_last_error(model));
	}
	return true;
}

// The particles of "fixed" are marked first and then fixed together (sm_model_set_motions), with
// the free particles numbered once.
bool sm_parser_read_fixed(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "fixed",
		                      "must be an array of particle references and boxes, not %s",
		                      sm_parser_type_name(list));
	sm_model* model = p->ex->model;
	bool* fix = calloc((size_t)model->particle_count + 1, sizeof(bool));
	if (fix == NULL)
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "fixed", "out of memory");
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
		sm_parser_child_index(path, "ports", k);
		const json_t* obj = json_array_get(list, k);
		if (!sm_parser_expect_object(p, obj, path) || !sm_parser_check_keys(p, obj, path, keys) ||
		    !sm_parser_require(p, obj, path, "name") || !sm_parser_require(p, obj, path, "particle") ||
		    !sm_parser_require(p, obj, path, "kind"))
			return false;
		sm_port port;
		sm_parser_child_key(sub, path, "name");
		if (!sm_parser_check_name(p, json_object_get(obj, "name"), sub, true, &port.name))
			return false;
		const int32_t same_name = sm_name_index_find(&p->ex->port_names, port.name, strlen(port.name));
		char text[TEXT_QUOTED_CAPACITY];
		if (same_name >= 0)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "port name %s is already used by ports[%d]",
			                      sm_text_quoted(text, port.name), (int)same_name);
		sm_parser_child_key(sub, path, "particle");
		if (!resolve_particle(p, json_object_get(obj, "particle"), sub, &port.particle))
			return false;
		const json_t* kind = json_object_get(obj, "kind");
		const char* k_name = json_is_string(kind) ? json_string_value(kind) : "";
		sm_parser_child_key(sub, path, "kind");
		if (strcmp(k_name, "force") == 0)
			port.kind = SM_PORT_FORCE;
		else if (strcmp(k_name, "motion") == 0)
			port.kind = SM_PORT_MOTION;
		else if (strcmp(k_name, "probe") == 0)
			port.kind = SM_PORT_PROBE;
		else
			return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be \"force\", \"motion\" or \"probe\"");
		sm_particle_def def;
		sm_model_get_particle(p->ex->model, port.particle, &def);
		char which[TEXT_QUOTED_CAPACITY + 32];
		describe_particle(p->ex, port.particle, which, sizeof which);
		if (port.kind == SM_PORT_FORCE && def.motion != SM_PARTICLE_FREE)
			return sm_parser_fail(
			    p, SM_ERROR_SCHEMA, path,
			    "a force port needs a free particle, and %s is fixed (use a motion or probe port)", which);
		// Only probe ports share a particle, so a particle has one port of another kind or probes
		// alone, and its first port says which.
		const int32_t q = port_at[port.particle];
		if (q >= 0 && (p->ex->ports[q].kind != SM_PORT_PROBE || port.kind != SM_PORT_PROBE))
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
			                      "%s already has port %s; only probe ports may share a particle", which,
			                      p->ex->ports[q].name);
		int32_t holder;
		p->ex->ports[p->ex->port_count] = port;
		if (!sm_name_index_insert(&p->ex->port_names, port.name, strlen(port.name), p->ex->port_count,
		                          &holder))
			return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "ports", "out of memory");
		if (q < 0)
			port_at[port.particle] = p->ex->port_count;
		p->ex->port_count++;
	}
	return true;
}

bool sm_parser_read_ports(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "ports", "must be an array of ports, not %s",
		                      sm_parser_type_name(list));
	const size_t n = json_array_size(list);
	if ((int64_t)n > p->doc->max_elements)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "ports", "too many ports (%zu)", n);
	const int32_t particles = sm_model_particle_count(p->ex->model);
	p->ex->ports = calloc(n > 0 ? n : 1, sizeof(sm_port));
	int32_t* port_at = malloc((size_t)(particles > 0 ? particles : 1) * sizeof(int32_t));
	if (p->ex->ports == NULL || port_at == NULL) {
		free(port_at);
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "ports", "out of memory");
	}
	for (int32_t i = 0; i < particles; i++)
		port_at[i] = -1;
	const bool ok = read_ports_to(p, list, port_at);
	free(port_at);
	return ok;
}

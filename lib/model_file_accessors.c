// Model files: the accessors of a loaded document (springmass/model_file.h): its name, parameters,
// ports, structures, particles and settings; setting its parameters, which evaluates the tree
// again, and its initial state; and its self-contained text, with the OBJ files of meshes inlined.
#define _POSIX_C_SOURCE 200809L  // newlocale, uselocale (c_locale.h)

#include "c_locale.h"
#include "model_file_internal.h"
#include "model_file_text.h"

#include "model_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
	return unit != NULL ? unit : sm_no_single_unit();
}

uint32_t sm_document_parameter_uses(const sm_document* doc, int32_t index)
{
	return doc != NULL && index >= 0 && index < doc->parameter_count ? doc->current->parameter_uses[index]
	                                                                 : 0;
}

int32_t sm_document_parameter_index(const sm_document* doc, const char* name)
{
	return doc != NULL && name != NULL ? sm_document_find_parameter(doc, name) : -1;
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
	expansion* ex = sm_document_expand(doc, copy, &local);
	if (ex == NULL) {
		// Name the parameters that changed, as the loader names those a value came from ("(with
		// parameter a = 1 and parameter b = 2)"), unless the message already names one of them.
		int32_t last = -1;
		bool named = false;
		for (int32_t k = 0; k < doc->parameter_count; k++) {
			if (same_value(copy[k], doc->parameter_values[k]))
				continue;
			char name[TEXT_QUOTED_CAPACITY + 16], cut[TEXT_QUOTED_CAPACITY];
			snprintf(name, sizeof name, "parameter %s = ", sm_text_cut(cut, doc->parameter_names[k]));
			named = named || strstr(local.message, name) != NULL;
			last = k;
		}
		char with[SM_ERROR_MESSAGE_CAPACITY] = "";
		size_t used = 0;
		for (int32_t k = 0, n = 0; k < doc->parameter_count && !named && used < sizeof with; k++) {
			if (same_value(copy[k], doc->parameter_values[k]))
				continue;
			const char* joint = n++ == 0 ? " (with " : k == last ? " and " : ", ";
			char value[SM_NUMBER_TEXT_CAPACITY], cut[TEXT_QUOTED_CAPACITY];
			sm_format_number(copy[k], value);
			const int written =
			    snprintf(with + used, sizeof with - used, "%sparameter %s = %s%s", joint,
				         sm_text_cut(cut, doc->parameter_names[k]), value, k == last ? ")" : "");
			used += written > 0 ? (size_t)written : 0;
		}
		free(copy);
		return sm_error_set(err, local.status, "%s%s", local.message, with);
	}
	sm_expansion_free(doc->current);
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
	_Static_assert(sizeof types / sizeof types[0] == STRUCTURE_TYPE_COUNT, "a name for every structure type");
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

const char* sm_document_structure_file_path(const sm_document* doc, int32_t index)
{
	if (doc == NULL || index < 0 || (size_t)index >= doc->mesh_file_slots || doc->mesh_files[index] == NULL)
		return NULL;
	return doc->mesh_files[index]->path;
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

void sm_document_potential_terms(const sm_document* doc, uint8_t* terms)
{
	if (doc == NULL || terms == NULL)
		return;
	const expansion* ex = doc->current;
	const sm_model* model = ex->model;
	// Every particle has a mass > 0: its weight has the components gravity has.
	uint8_t weight = 0;
	for (int c = 0; c < 3; c++)
		if (model->def.gravity[c] != 0.0 || ex->gravity_source[c] >= 0)
			weight |= (uint8_t)(SM_POTENTIAL_CONSTANT_X << c);
	for (int32_t i = 0; i < model->particle_count; i++)
		terms[i] = weight;
	for (int32_t k = 0; k < ex->load_count; k++) {
		const document_load* load = &ex->loads[k];
		for (int c = 0; c < 3; c++)
			if (load->force[c] != 0.0 || load->source[c] >= 0)
				terms[load->particle] |= (uint8_t)(SM_POTENTIAL_CONSTANT_X << c);
	}
	for (int32_t s = 0; s < model->spring_count; s++) {
		if (model->stiffness[s] != 0.0 || ex->spring_sources[s].stiffness >= 0) {
			terms[model->spring_a[s]] |= SM_POTENTIAL_ELASTIC;
			terms[model->spring_b[s]] |= SM_POTENTIAL_ELASTIC;
		}
	}
}

bool sm_document_force_terms(const sm_document* doc, uint8_t* terms)
{
	if (doc == NULL)
		return false;
	const expansion* ex = doc->current;
	const sm_model* model = ex->model;
	for (int32_t s = 0; terms != NULL && s < model->spring_count; s++) {
		const spring_source* src = &ex->spring_sources[s];
		terms[s] = (uint8_t)(((model->stiffness[s] != 0.0 || src->stiffness >= 0) ? SM_FORCE_ELASTIC : 0) |
		                     ((model->damping[s] != 0.0 || src->damping >= 0) ? SM_FORCE_DAMPING : 0));
	}
	return model->def.mass_damping != 0.0 || ex->mass_damping_source >= 0;
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
	return doc != NULL && name != NULL ? sm_expansion_lookup_name(doc->current, name) : -1;
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
	expansion* ex = sm_document_expand(doc, doc->parameter_values, &local);
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
	sm_expansion_free(ex);
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

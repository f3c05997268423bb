// Model files: "structures". A rope, sheet, block or mesh (its vertices and triangles given in the
// file or read from an OBJ file when the document was parsed) is checked against the document's
// limit, built by its builder (structures.h), and its particles named name[i], name[row,column]
// or name[row,column,layer]; each spring's constants are noted as coming from its group.
#include "model_file_parser.h"
#include "model_file_text.h"

#include "structures_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
	sm_parser_child_key(sub, path, key);
	if (!sm_parser_expect_object(p, value, sub) || !sm_parser_check_keys(p, value, sub, keys))
		return false;
	// A group that gives neither constant makes no springs: a forgotten stiffness, not a choice
	// (zeros given make none too, as asked).
	bool constants = false;
	for (const char* const* k = keys; *k != NULL; k++)
		constants = constants || (strcmp(*k, "break_strain") != 0 && json_object_get(value, *k) != NULL);
	if (!constants)
		return sm_parser_fail(
		    p, SM_ERROR_SCHEMA, sub,
		    "gives no stiffness and no damping, so it would make no springs (give stiffness, "
		    "strain_stiffness or section_stiffness, or a damping; or leave the group out)");
	if (!sm_parser_read_constants(p, value, sub, m, src))
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
		return sm_parser_fail(
		    p, SM_ERROR_SCHEMA, path,
		    "the model would have %lld particles and %lld springs, more than the limit of %lld of each",
		    (long long)np, (long long)ns, limit);
	if (np > limit || ns > limit)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
		                      "the model would have %lld %s, more than the limit of %lld",
		                      (long long)(np > limit ? np : ns), np > limit ? "particles" : "springs", limit);
	return sm_parser_reserve(p, np, ns);
}

// Mesh vertices [[x, y, z], ...] and triangles [[a, b, c], ...], copied into arrays.
static bool read_mesh_arrays(parser* p, const json_t* obj, const char* path, double** vertices,
                             int32_t* vertex_count, int32_t** triangles, int32_t* triangle_count)
{
	char sub[PATH_CAPACITY];
	const json_t* vs = json_object_get(obj, "vertices");
	const json_t* ts = json_object_get(obj, "triangles");
	sm_parser_child_key(sub, path, "vertices");
	if (!json_is_array(vs))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be an array of [x, y, z] vertices, not %s",
		                      sm_parser_type_name(vs));
	sm_parser_child_key(sub, path, "triangles");
	if (!json_is_array(ts))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub,
		                      "must be an array of [a, b, c] vertex index triples, not %s",
		                      sm_parser_type_name(ts));
	// The springs are counted once the mesh is built (its edges are known then).
	const size_t nv = json_array_size(vs), nt = json_array_size(ts);
	if (!check_budget(p, path, (int64_t)nv, 0))
		return false;
	*vertices = malloc((nv > 0 ? nv : 1) * 3 * sizeof(double));
	*triangles = malloc((nt > 0 ? nt : 1) * 3 * sizeof(int32_t));
	if (*vertices == NULL || *triangles == NULL)
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory for %zu vertices", nv);
	for (size_t v = 0; v < nv; v++) {
		char element[PATH_CAPACITY];
		snprintf(element, sizeof element, "%.100s.vertices[%zu]", path, v);
		const json_t* vector = json_array_get(vs, v);
		if (!json_is_array(vector) || json_array_size(vector) != 3)
			return sm_parser_fail(
			    p, SM_ERROR_SCHEMA, element, "must be an array of 3 numbers [x, y, z], not %s%s",
			    sm_parser_type_name(vector), json_is_array(vector) ? " of another length" : "");
		for (size_t c = 0; c < 3; c++) {
			char coordinate[PATH_CAPACITY];
			sm_parser_child_index(coordinate, element, c);
			double x = 0.0;
			int32_t source;
			if (!sm_parser_read_number(p, FEEDS_STATE, "m", json_array_get(vector, c), coordinate, &x,
			                           &source) ||
			    !sm_parser_check_rule(p, coordinate, x, source, ANY_FINITE))
				return false;
			(*vertices)[3 * v + c] = x;
		}
	}
	for (size_t t = 0; t < nt; t++) {
		char element[PATH_CAPACITY];
		snprintf(element, sizeof element, "%.100s.triangles[%zu]", path, t);
		const json_t* triple = json_array_get(ts, t);
		if (json_is_array(triple) && json_array_size(triple) != 3)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, element,
			                      "must be an array of 3 vertex indices, not of %zu",
			                      json_array_size(triple));
		if (!json_is_array(triple))
			return sm_parser_fail(p, SM_ERROR_SCHEMA, element, "must be an array of 3 vertex indices, not %s",
			                      sm_parser_type_name(triple));
		for (size_t c = 0; c < 3; c++) {
			char corner[PATH_CAPACITY];
			sm_parser_child_index(corner, element, c);
			int64_t index;
			if (!sm_parser_read_count(p, FEEDS_COUNTS, json_array_get(triple, c), corner, 0,
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
			const int32_t k = name != NULL ? sm_document_find_parameter(p->doc, name) : -1;
			if (k >= 0)
				sm_parser_note_parameter(noted, k);
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
		sm_parser_child_key(sub, path, "mass_distribution");
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be \"even\" or \"lumped\"");
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
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "particles", "out of memory");
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
			return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, "particles", "out of memory");
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
	sm_parser_child_index(path, "particles", k);
	sm_parser_child_key(sub, path, "name");
	return sm_parser_fail(
	    p, SM_ERROR_SCHEMA, sub,
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
	sm_parser_forget_parameters(p);
	if (!sm_parser_expect_object(p, obj, path) || !sm_parser_require(p, obj, path, "type") ||
	    !sm_parser_require(p, obj, path, "name"))
		return false;
	const json_t* type = json_object_get(obj, "type");
	const char* t = json_is_string(type) ? json_string_value(type) : "";
	sm_parser_child_key(sub, path, "type");
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
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "must be \"rope\", \"sheet\", \"block\" or \"mesh\"");
	const char* const* keys[] = {rope_keys, sheet_keys, block_keys, mesh_keys};
	_Static_assert(sizeof keys / sizeof keys[0] == STRUCTURE_TYPE_COUNT, "keys for every structure type");
	if (!sm_parser_check_keys(p, obj, path, keys[s.type]))
		return false;
	sm_parser_child_key(sub, path, "name");
	if (!sm_parser_check_name(p, json_object_get(obj, "name"), sub, true, &s.name))
		return false;
	const size_t name_bytes = strlen(s.name);
	char text[TEXT_QUOTED_CAPACITY];
	if (name_bytes > MAX_STRUCTURE_NAME_BYTES)
		return sm_parser_fail(
		    p, SM_ERROR_SCHEMA, sub,
		    "structure name %s has %zu bytes; a structure's name may have at most %d, so that its "
		    "particles' names (name[row,column,layer]) fit in %d",
		    sm_text_quoted(text, s.name), name_bytes, MAX_STRUCTURE_NAME_BYTES, MAX_NAME_BYTES);
	if (sm_parser_find_structure(p->ex, s.name, name_bytes) != NULL)
		return sm_parser_fail(p, SM_ERROR_SCHEMA, sub, "structure name %s is already used",
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
		if (!sm_parser_require(p, obj, path, "start") || !sm_parser_require(p, obj, path, "end") ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "start", ANY_FINITE, d.start, NULL) ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "end", ANY_FINITE, d.end, NULL) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "segments", 1, limit, &segments) ||
		    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "mass_per_length", POSITIVE,
		                          &d.mass_per_length, NULL) ||
		    !read_material(p, obj, path, "structural", &d.structural, &groups[0]) ||
		    !read_material(p, obj, path, "bending", &d.bending, &groups[1]))
			return false;
		if (json_object_get(obj, "mass") != NULL && json_object_get(obj, "mass_per_length") != NULL)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
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
		if (!sm_parser_read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, d.origin, NULL) ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "edge_u", ANY_FINITE, d.edge_u,
		                           edge_sources[0]) ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "edge_v", ANY_FINITE, d.edge_v,
		                           edge_sources[1]) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "nu", 2, limit, &nu) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "nv", 2, limit, &nv) ||
		    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !read_material(p, obj, path, "structural", &d.structural, &groups[0]) ||
		    !read_material(p, obj, path, "shear", &d.shear, &groups[1]) ||
		    !read_material(p, obj, path, "bend", &d.bend, &groups[2]))
			return false;
		static const char* const edge_keys[2] = {"edge_u", "edge_v"};
		for (int e = 0; e < 2; e++) {
			const double* edge = e == 0 ? d.edge_u : d.edge_v;
			if (edge[0] == 0.0 && edge[1] == 0.0 && edge[2] == 0.0) {
				char text[PATH_CAPACITY], vector[3 * DESCRIPTION_CAPACITY + 8];
				sm_parser_child_key(text, path, edge_keys[e]);
				return sm_parser_fail(
				    p, SM_ERROR_INVALID_ARGUMENT, text,
				    "%s m is zero: the sheet spans no area and its particles would coincide",
				    sm_parser_describe_vector(p, vector, sizeof vector, edge, edge_sources[e]));
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
		if (!sm_parser_require(p, obj, path, "size") ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, d.origin, NULL) ||
		    !sm_parser_read_vector(p, FEEDS_STATE, obj, path, "size", POSITIVE, d.size, NULL) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "nu", 2, limit, &nu) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "nv", 2, limit, &nv) ||
		    !sm_parser_read_count_field(p, FEEDS_COUNTS, obj, path, "nw", 2, limit, &nw) ||
		    !sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "mass", POSITIVE, &d.mass, NULL) ||
		    !read_material(p, obj, path, "edge", &d.edge, &groups[0]) ||
		    !read_material(p, obj, path, "face_diagonal", &d.face_diagonal, &groups[1]) ||
		    !read_material(p, obj, path, "body_diagonal", &d.body_diagonal, &groups[2]))
			return false;
		if (nu * nv > limit || nu * nv * nw > limit)
			return sm_parser_fail(p, SM_ERROR_SCHEMA, path,
			                      "%lld x %lld x %lld particles exceed the limit of %lld", (long long)nu,
			                      (long long)nv, (long long)nw, (long long)limit);
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
		    (from != NULL ||
			 (sm_parser_require(p, obj, path, "vertices") && sm_parser_require(p, obj, path, "triangles"))) &&
		    sm_parser_read_field(p, FEEDS_CONSTANTS, obj, path, "density", POSITIVE, &d.density, NULL) &&
		    sm_parser_read_field(p, FEEDS_STATE, obj, path, "scale", POSITIVE, &scale, NULL) &&
		    sm_parser_read_vector(p, FEEDS_STATE, obj, path, "origin", ANY_FINITE, origin, NULL) &&
		    read_material(p, obj, path, "edge", &d.edge, &groups[0]) &&
		    read_material(p, obj, path, "bend", &d.bend, &groups[1]);
		if (ok && from != NULL) {
			d.vertex_count = from->mesh.vertex_count;
			d.triangle_count = from->mesh.triangle_count;
			vertices = malloc(3 * (size_t)(d.vertex_count > 0 ? d.vertex_count : 1) * sizeof(double));
			ok = check_budget(p, path, d.vertex_count, 0) &&
			     (vertices != NULL || sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path,
			                                         "out of memory for %d vertices", (int)d.vertex_count));
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
			return sm_parser_fail_naming(p, st, path, sm_model_last_error(model), &repeating);
		// A failure about one triangle or vertex of an OBJ file: at the line of its face or vertex.
		const int32_t* place = from == NULL ? NULL
		                       : failed_triangle >= 0
		                           ? from->mesh.triangle_place + 2 * (size_t)failed_triangle
		                       : failed_vertex >= 0 ? from->mesh.vertex_place + 2 * (size_t)failed_vertex
		                                            : NULL;
		if (st != SM_OK && place != NULL) {
			char sub_file[PATH_CAPACITY], message[SM_ERROR_MESSAGE_CAPACITY];
			sm_parser_child_key(sub_file, path, "file");
			snprintf(message, sizeof message, "%s:%d:%d: %s", from->shown, (int)place[0], (int)place[1],
			         sm_model_last_error(model));
			return sm_parser_fail_naming_parameters(p, st, sub_file, message);
		}
		// The mesh's particles are within the limit; its springs are counted now.
		if (st == SM_OK && !check_budget(p, path, 0, 0))
			return false;
		break;
	}
	}
	p->section_dimension = 0;
	if (st != SM_OK)
		return sm_parser_fail_naming_parameters(p, st, path, sm_model_last_error(model));

	// Record the structure, name its particles and note the sources of its springs' constants.
	expansion* ex = p->ex;
	int32_t holder;
	void* spare;
	if (!GROW_ARRAY(ex->structures, &ex->structure_capacity, ex->structure_count + 1, spare))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory");
	ex->structures[ex->structure_count] = s;
	if (!sm_name_index_insert(&ex->structure_names, s.name, strlen(s.name), ex->structure_count, &holder))
		return sm_parser_fail(p, SM_ERROR_OUT_OF_MEMORY, path, "out of memory");
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
			ok = sm_parser_name_particle(p, sub, index, "%s[%d,%d]", s.name, (int)row, (int)column);
		else if (s.type == STRUCTURE_BLOCK)
			ok = sm_parser_name_particle(p, sub, index, "%s[%d,%d,%d]", s.name, (int)row, (int)column,
			                             (int)layer);
		else
			ok = sm_parser_name_particle(p, sub, index, "%s[%d]", s.name, (int)k);
		if (!ok)
			return false;
	}
	for (int32_t k = 0; k < r->spring_count; k++)
		p->ex->spring_sources[s0 + k] = groups[spring_group(&s, model, s0 + k)];
	return true;
}

bool sm_parser_read_structures(parser* p, const json_t* list)
{
	if (list == NULL)
		return true;
	if (!json_is_array(list))
		return sm_parser_fail(p, SM_ERROR_SCHEMA, "structures", "must be an array of structures, not %s",
		                      sm_parser_type_name(list));
	named_like_references like = {.prefixes = NULL};
	sm_name_index_init(&like.index, named_like_prefix, &like);
	bool ok = find_names_like_references(p, &like);
	for (size_t k = 0; ok && k < json_array_size(list); k++) {
		char path[PATH_CAPACITY];
		sm_parser_child_index(path, "structures", k);
		ok = read_structure(p, &like, k, json_array_get(list, k), path);
	}
	named_like_free(&like);
	return ok;
}

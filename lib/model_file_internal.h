// Internal layout of sm_document, shared by the reader (model_file.c and the parts that
// model_file_parser.h lists), the accessors (model_file_accessors.c) and the writer
// (model_file_save.c).
//
// A document keeps the parsed JSON tree and the parameters' current values. Everything else is
// an "expansion": the tree evaluated with those values into a model, the particles' names,
// the ports and the settings, plus where each constant came from (which parameter, if any) so
// that saving can keep parameter references. Changing a parameter evaluates the tree again
// into a new expansion and swaps it in only if it is valid.
#pragma once

#include "mesh_file.h"
#include "name_index.h"
#include "springmass/model_file.h"
#include "springmass/structures.h"

#include <jansson.h>

// Default limit on particles and on springs of one document (each).
#define SM_DOCUMENT_MAX_ELEMENTS (1 << 22)

// One entry of "loads": a force [N] on a particle, each component from a parameter (its index) or
// a number (-1).
typedef struct document_load {
	int32_t particle;
	double force[3];
	int32_t source[3];
} document_load;

// Where a particle's values came from: a parameter index, or -1 for a number.
typedef struct particle_source {
	int32_t mass;
	int32_t position[3];
	int32_t velocity[3];
} particle_source;

// Where a spring's constants came from: a parameter index, or -1 for a number (or a value the
// loader derived, such as a rest length taken from the initial distance).
typedef struct spring_source {
	int32_t rest_length;
	int32_t stiffness;
	int32_t damping;
	int32_t break_strain;
	int32_t section;
	bool kind_given;  // the file gave "kind": the rest length's parameter then chooses no law
} spring_source;

typedef enum structure_type {
	STRUCTURE_ROPE,
	STRUCTURE_SHEET,
	STRUCTURE_BLOCK,
	STRUCTURE_MESH
} structure_type;
// The number of types: the tables indexed by a type (its name, its keys, its index forms) have
// this many entries, which each checks at compile time.
#define STRUCTURE_TYPE_COUNT (STRUCTURE_MESH + 1)

typedef struct document_structure {
	const char* name;  // points into the JSON tree
	structure_type type;
	sm_structure range;
} document_structure;

// The OBJ file a mesh structure gives as its "file", read when the document is parsed: a
// parameter change builds the mesh again from it, without reading the file again.
typedef struct document_mesh_file {
	char* path;   // the path it was read from: "file" joined to the model file's folder
	char* shown;  // that path as messages show it, escaped, a long one by its end
	mesh_file mesh;
} document_mesh_file;

typedef struct expansion {
	sm_model* model;
	particle_source* particle_sources;  // one per particle
	spring_source* spring_sources;      // one per spring
	int64_t particle_capacity, spring_capacity;

	// Particle names: offsets into `names` (-1 for an unnamed particle), and the index from name
	// to particle.
	int64_t* name_offset;
	char* names;
	int64_t names_length, names_capacity;
	name_index particle_names;

	document_structure* structures;
	int64_t structure_capacity;
	int32_t structure_count;
	name_index structure_names;

	document_load* loads;  // as the file gives them, for the canonical writer
	int32_t load_count;
	int32_t gravity_source[3];    // each component's parameter, or -1 for a number
	int32_t mass_damping_source;  // mass_damping's parameter, or -1 for a number

	sm_port* ports;  // names point into the JSON tree
	int32_t port_count;
	name_index port_names;

	sm_document_settings settings;

	uint8_t* parameter_uses;  // per parameter: sm_parameter_use flags of the places naming it
	// Per parameter: the unit of every value naming it, "" for several or for counts and indices,
	// NULL while unused (static strings).
	const char** parameter_units;
} expansion;

struct sm_document {
	json_t* root;
	char* source;  // file name used in messages
	const char* name;
	const char* description;

	int32_t parameter_count;
	const char** parameter_names;  // point into the JSON tree
	double* parameter_values;
	name_index parameter_index;  // name to parameter
	// Per parameter: the unit "parameter_units" gives it (a static string), NULL if none. It is
	// the parameter's unit: every value naming it whose key tells a unit must be in that one.
	const char** parameter_declared_units;

	expansion* current;

	// Initial state set by sm_document_set_initial_state (NULL if none): 3 per particle.
	double* initial_position;
	double* initial_velocity;
	int32_t initial_count;

	int64_t max_elements;

	// Per entry of "structures": the OBJ file it reads, or NULL.
	document_mesh_file** mesh_files;
	size_t mesh_file_slots;
};

// sm_document_parse with a limit on particles and springs (each) other than the default, for
// the fuzz target, which must not spend its time building enormous grids.
sm_document* sm_document_parse_limited(const char* text, size_t length, const char* source_name,
                                       int64_t max_elements, sm_error* err);

// Steps of the reader that the accessors use too.

// Evaluates the document's tree with the given parameter values into a new expansion
// (model_file.c); NULL, with err filled, on failure.
expansion* sm_document_expand(const sm_document* doc, const double* parameter_values, sm_error* err);
// Frees ex and all it holds; NULL is allowed (model_file_elements.c).
void sm_expansion_free(expansion* ex);
// The particle that has the name, or -1 (model_file_elements.c).
int32_t sm_expansion_lookup_name(const expansion* ex, const char* name);
// The parameter that has the name, or -1 (model_file_values.c).
int32_t sm_document_find_parameter(const sm_document* doc, const char* name);
// The unit of parameters that stand for values of different units, or for counts and indices.
// Not an array shared by the files: a global array of the library comes with a second global
// symbol in the sanitizer builds (AddressSanitizer's __odr_asan.<name>), which lacks the sm_
// prefix every global symbol of the library has (tests/check_symbols.sh).
static inline const char* sm_no_single_unit(void)
{
	return "";
}

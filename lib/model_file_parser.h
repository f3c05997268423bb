// Model files: what the parts of the reader share. The state of one evaluation of the tree is a
// parser; a step that breaks off records its message with sm_parser_fail and returns false.
//
//   model_file.c             the driver: the text parsed into a tree, the header and parameters,
//                            the OBJ files of meshes, the settings, the tree evaluated into an
//                            expansion, files loaded
//   model_file_values.c      reading and checking values: numbers or the parameters standing for
//                            them, the rules they obey, fields, counts, vectors, names; paths
//   model_file_elements.c    the expansion's storage, particle names and references, and
//                            "particles", "springs", "fixed", "loads" and "ports"
//   model_file_structures.c  "structures": ropes, sheets, blocks and meshes
#pragma once

#include "model_file_internal.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// Room for a path in the document such as `structures[2].edge.strain_stiffness`.
#define PATH_CAPACITY 160
// Longest particle, port or parameter name [bytes].
#define MAX_NAME_BYTES 200
// Room for "parameter NAME = VALUE" (sm_parser_describe) with the longest name [bytes].
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

// Failing with a path, and reading and checking values (model_file_values.c).

// Records the first failure: "<source>: <path>: <message>".
bool sm_parser_fail(parser* p, sm_status status, const char* path, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
void sm_parser_child_key(char* out, const char* path, const char* key);
void sm_parser_child_index(char* out, const char* path, size_t index);
const char* sm_parser_type_name(const json_t* value);
bool sm_parser_expect_object(parser* p, const json_t* value, const char* path);
bool sm_parser_check_keys(parser* p, const json_t* obj, const char* path, const char* const* allowed);
void sm_parser_note_parameter(noted_parameters* noted, int32_t k);
void sm_parser_note_unit(expansion* ex, int32_t k, const char* unit);
const char* sm_parser_declared_unit(const parser* p, int32_t k);
bool sm_parser_read_number(parser* p, feeds use, const char* unit, const json_t* value, const char* path,
                           double* out, int32_t* source);
const char* sm_parser_describe(parser* p, char* buffer, size_t size, double value, int32_t source);
const char* sm_parser_describe_vector(parser* p, char* buffer, size_t size, const double v[3],
                                      const int32_t sources[3]);
void sm_parser_forget_parameters(parser* p);
bool sm_parser_fail_naming(parser* p, sm_status status, const char* path, const char* message,
                           const noted_parameters* noted);
bool sm_parser_fail_naming_parameters(parser* p, sm_status status, const char* path, const char* message);
bool sm_parser_check_rule(parser* p, const char* path, double v, int32_t source, number_rule rule);
bool sm_parser_read_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                          number_rule rule, double* out, int32_t* source);
bool sm_parser_require(parser* p, const json_t* obj, const char* path, const char* key);
bool sm_parser_read_count(parser* p, feeds use, const json_t* value, const char* path, int64_t lo, int64_t hi,
                          int64_t* out);
bool sm_parser_read_count_field(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                                int64_t lo, int64_t hi, int64_t* out);
bool sm_parser_read_vector(parser* p, feeds use, const json_t* obj, const char* path, const char* key,
                           number_rule rule, double out[3], int32_t sources[3]);
bool sm_parser_read_bool(parser* p, const json_t* obj, const char* path, const char* key, bool* out);
bool sm_parser_check_name_text(parser* p, const char* s, size_t n, const char* path, bool identifier);
bool sm_parser_check_name(parser* p, const json_t* value, const char* path, bool identifier,
                          const char** out);

// The expansion's storage, particle names and references, and the elements read one by one
// (model_file_elements.c).

bool sm_parser_grow_array(void* array, int64_t* capacity, int64_t needed, size_t size, void** grown);
// sm_parser_grow_array on `array`, a pointer of any type, assigned as its own type (written through a
// void** it would break C's aliasing rules) by way of the caller's void* `spare`.
#define GROW_ARRAY(array, capacity, needed, spare)                                                           \
	(sm_parser_grow_array((array), (capacity), (needed), sizeof *(array), &(spare)) &&                       \
	 ((array) = (spare), true))
bool sm_parser_reserve(parser* p, int64_t particles, int64_t springs);
const char* sm_parser_particle_name(const void* owner, int32_t particle);
const char* sm_parser_structure_name(const void* owner, int32_t structure);
const char* sm_parser_port_name(const void* owner, int32_t port);
const char* sm_parser_parameter_name(const void* owner, int32_t parameter);
// Gives particle `index` the name (formatted); fails if the name is taken.
bool sm_parser_name_particle(parser* p, const char* path, int32_t index, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
const document_structure* sm_parser_find_structure(const expansion* ex, const char* name, size_t length);
bool sm_parser_read_particles(parser* p, const json_t* list);
bool sm_parser_read_constants(parser* p, const json_t* obj, const char* path, sm_spring_material* m,
                              spring_source* src);
bool sm_parser_read_springs(parser* p, const json_t* list);
bool sm_parser_read_fixed(parser* p, const json_t* list);
bool sm_parser_read_loads(parser* p, const json_t* list);
bool sm_parser_read_ports(parser* p, const json_t* list);

// Structures (model_file_structures.c).

bool sm_parser_read_structures(parser* p, const json_t* list);

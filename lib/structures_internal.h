// Steps shared by the structure builders (structures.c, mesh.c): checks, appending with
// messages that name the structure, and the roll-back to the counts before a failed call.
#pragma once

#include "model_internal.h"
#include "springmass/structures.h"

#include <stdlib.h>

bool sm_structure_material_present(const sm_spring_material* m);
// Checks a group's constants; `sections` says whether the structure has a cross-section, which
// SM_PER_SECTION constants need (a sheet, block or mesh; not a rope).
sm_status sm_structure_check_material(sm_model* model, const char* what, const char* group,
                                      const sm_spring_material* m, bool sections);
sm_status sm_structure_check_vector(sm_model* model, const char* what, const char* field, const double v[3]);
// Fails if the structure or the grown model would exceed SM_STRUCTURE_MAX_ELEMENTS.
sm_status sm_structure_check_size(sm_model* model, const char* what, int64_t particles, int64_t springs);
// Cuts the model back to the given counts (the counts it had before a failed builder call).
void sm_structure_truncate(sm_model* m, int32_t particles, int32_t springs);
// Describes the structure just built in *out (may be NULL): particles from p0, springs from s0 to
// the model's count, the grid shape and the springs made of each group.
void sm_structure_fill_out(sm_structure* out, int32_t p0, int32_t s0, const sm_model* model, int32_t n0,
                           int32_t n1, int32_t n2, const int32_t group_springs[3]);
sm_status sm_structure_add_particle(sm_model* model, const char* what, double mass, const double position[3]);
// Adds a spring of the group between particles a and b (already added). `measure` is the area
// [m^2] (sheet, mesh) or volume [m^3] (block) the spring stands for: per-section constants
// (SM_PER_SECTION) get the section measure / |x_b - x_a|. Fails, naming `inputs` (the fields
// that set the structure's size, "edge_u, edge_v, nu and nv"), if the spring's length is beyond
// what a model holds (its square not a finite normal double) or its section not finite and > 0.
sm_status sm_structure_add_spring(sm_model* model, const char* what, const char* inputs, const char* group,
                                  int32_t a, int32_t b, const sm_spring_material* m, double measure);

// sm_add_mesh; on a failure about one triangle of the definition (a repeated vertex, zero area, an
// edge shared by more than two triangles, a repeated triangle; the first triangle when there are
// fewer than 3 vertices) *triangle is its index, on one
// about one vertex (a coordinate that is not finite, no triangle, a mass beyond a double)
// *vertex; -1 otherwise (a model file names the line of an OBJ file that gave it).
sm_status sm_add_mesh_located(sm_model* model, const sm_mesh_def* def, sm_structure* out, int32_t* triangle,
                              int32_t* vertex);

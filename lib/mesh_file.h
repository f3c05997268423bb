// Triangle meshes from Wavefront OBJ text, the format modellers (Blender, MeshLab, gmsh) export:
// the subset docs/model-format.md describes (`v` and `f` statements; faces of more than three
// vertices cut into triangles as fans; the statements that carry no geometry ignored, every
// other one refused), for a mesh structure's "file".
#pragma once

#include "springmass/base.h"

#include <stddef.h>
#include <stdint.h>

// Most bytes of a message from sm_mesh_file_parse, NUL included.
#define MESH_FILE_MESSAGE_CAPACITY 256

// A mesh as an OBJ file gives it, with where each vertex and triangle is in the file.
typedef struct mesh_file {
	double* vertices;  // 3 per vertex, the file's numbers as they are
	int32_t vertex_count;
	int32_t* triangles;  // 3 vertex indices (from 0) per triangle
	int32_t triangle_count;
	int32_t* vertex_place;    // line and column (from 1) of each vertex's `v`, 2 per vertex
	int32_t* triangle_place;  // line and column of the `f` each triangle was cut from, 2 per triangle
} mesh_file;

// Reads OBJ text of `length` bytes into *out: at most max_vertices vertices and max_triangles
// triangles (refused past them before anything is allocated). On failure *out is empty, *line
// and *column (from 1, as an editor shows them: LF, CR LF and a lone CR end a line, columns count
// UTF-8 characters) place the fault, and message (MESH_FILE_MESSAGE_CAPACITY bytes) says the rule:
// SM_ERROR_SYNTAX for text that is not the OBJ subset, SM_ERROR_NOT_FINITE for a coordinate beyond
// a double, SM_ERROR_PARTICLE_INDEX for a face's vertex that is not in the file, SM_ERROR_SCHEMA
// for a file past the limits or with no face, SM_ERROR_OUT_OF_MEMORY.
sm_status sm_mesh_file_parse(const char* text, size_t length, int64_t max_vertices, int64_t max_triangles,
                             mesh_file* out, int* line, int* column, char* message);

// Frees what *mesh holds and empties it; accepts an empty one.
void sm_mesh_file_free(mesh_file* mesh);

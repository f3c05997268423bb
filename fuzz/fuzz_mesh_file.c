// libFuzzer target for the OBJ reader of a mesh's "file" (lib/mesh_file.c): any input must either
// be refused with a status, a message and a place within the text, or give vertices and triangles
// within the limits, every coordinate finite, every index a vertex of the file and every place a
// line of the text; the mesh builder then either takes them or refuses them with a message, and a
// mesh it takes has one particle per vertex.
#include "mesh_file.h"
#include "structures_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Limits far below the library's: the fuzzer looks for wrong handling of input, not for the time
// a mesh of millions of triangles takes.
#define FUZZ_MAX_VERTICES 2000
#define FUZZ_MAX_TRIANGLES 4000

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	mesh_file mesh;
	int line, column;
	char message[MESH_FILE_MESSAGE_CAPACITY];
	const char* text = (const char*)data;
	const sm_status st =
	    sm_mesh_file_parse(text, size, FUZZ_MAX_VERTICES, FUZZ_MAX_TRIANGLES, &mesh, &line, &column, message);
	// Lines end in LF, CR LF or CR: there are at most one more than the line ends.
	int64_t lines = 1;
	for (size_t k = 0; k < size; k++)
		lines += text[k] == '\n' || (text[k] == '\r' && (k + 1 == size || text[k + 1] != '\n'));
	if (st != SM_OK) {
		if (message[0] == '\0' || line < 0 || line > lines || (line > 0 && column < 1) ||
		    mesh.vertices != NULL)
			abort();  // a refusal must say why and where, and hold nothing
		return 0;
	}
	if (mesh.vertex_count > FUZZ_MAX_VERTICES || mesh.triangle_count < 1 ||
	    mesh.triangle_count > FUZZ_MAX_TRIANGLES)
		abort();
	for (int32_t v = 0; v < mesh.vertex_count; v++) {
		for (int c = 0; c < 3; c++)
			if (!isfinite(mesh.vertices[3 * (size_t)v + c]))
				abort();
		if (mesh.vertex_place[2 * (size_t)v] < 1 || mesh.vertex_place[2 * (size_t)v] > lines ||
		    mesh.vertex_place[2 * (size_t)v + 1] < 1)
			abort();
	}
	for (int32_t t = 0; t < mesh.triangle_count; t++) {
		for (int c = 0; c < 3; c++)
			if (mesh.triangles[3 * (size_t)t + c] < 0 ||
			    mesh.triangles[3 * (size_t)t + c] >= mesh.vertex_count)
				abort();
		if (mesh.triangle_place[2 * (size_t)t] < 1 || mesh.triangle_place[2 * (size_t)t] > lines ||
		    mesh.triangle_place[2 * (size_t)t + 1] < 1)
			abort();
	}
	sm_error err;
	sm_model_def def = sm_default_model_def();
	sm_model* model = sm_model_create(&def, &err);
	if (model == NULL)
		abort();
	sm_mesh_def d = sm_default_mesh_def();
	d.vertices = mesh.vertices;
	d.vertex_count = mesh.vertex_count;
	d.triangles = mesh.triangles;
	d.triangle_count = mesh.triangle_count;
	d.bend.stiffness = 1.0;
	int32_t triangle, vertex;
	const sm_status built = sm_add_mesh_located(model, &d, NULL, &triangle, &vertex);
	if (built != SM_OK && (sm_model_last_error(model)[0] == '\0' || triangle >= mesh.triangle_count ||
	                       vertex >= mesh.vertex_count || (triangle >= 0 && vertex >= 0)))
		abort();
	if (built == SM_OK && sm_model_particle_count(model) != mesh.vertex_count)
		abort();
	sm_model_destroy(model);
	sm_mesh_file_free(&mesh);
	return 0;
}

// Meshes from Wavefront OBJ files (a mesh structure's "file"): an OBJ file loads to exactly the model
// of the same vertices and triangles given inline, whatever forms its faces take; scale and origin
// place it; the canonical form and the self-contained text load without it; and a table of broken
// files gives exactly the expected errors, at the OBJ file's line and column.
#define _XOPEN_SOURCE 700  // mkdtemp, mkfifo, nftw, M_PI

#include "springmass/model_file.h"
#include "springmass/structures.h"
#include "test_harness.h"

#include <ftw.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

// The folder the tests write their files into (below the working folder), and the working folder.
static char work[64] = "";
static char home[4096] = "";

// Writes text into the file `name` of the work folder.
static int write_file(const char* name, const char* text)
{
	char path[256];
	snprintf(path, sizeof path, "%s/%s", work, name);
	FILE* f = fopen(path, "wb");
	if (f == NULL)
		return 1;
	const size_t n = strlen(text);
	const int wrong = fwrite(text, 1, n, f) != n;
	return fclose(f) != 0 || wrong;
}

// Loads the model text `json` as the file `name` of the work folder (its OBJ files beside it).
static sm_document* load_model(const char* name, const char* json, sm_error* err)
{
	if (write_file(name, json) != 0)
		return NULL;
	char path[256];
	snprintf(path, sizeof path, "%s/%s", work, name);
	sm_document* doc = sm_document_load(path, err);
	if (doc == NULL)
		printf("  %s\n", err->message);
	return doc;
}

static sm_document* parse_text(const char* json, sm_error* err)
{
	sm_document* doc = sm_document_parse(json, strlen(json), "inline.json", err);
	if (doc == NULL)
		printf("  %s\n", err->message);
	return doc;
}

// Two documents build the same model, bit for bit: every particle's mass, position, velocity and
// motion, every spring's ends, law, rest length, section and constants; and the same names.
static int same_model(const sm_document* a, const sm_document* b)
{
	sm_model *ma = NULL, *mb = NULL;
	ENSURE_STATUS(sm_document_build(a, &ma, NULL), SM_OK);
	ENSURE_STATUS(sm_document_build(b, &mb, NULL), SM_OK);
	int result = 0;
	if (sm_model_particle_count(ma) != sm_model_particle_count(mb) ||
	    sm_model_spring_count(ma) != sm_model_spring_count(mb))
		result = 1;
	for (int32_t i = 0; result == 0 && i < sm_model_particle_count(ma); i++) {
		sm_particle_def p, q;
		sm_model_get_particle(ma, i, &p);
		sm_model_get_particle(mb, i, &q);
		const char *na = sm_document_particle_name(a, i), *nb = sm_document_particle_name(b, i);
		if (memcmp(&p.mass, &q.mass, sizeof p.mass) != 0 || p.motion != q.motion ||
		    memcmp(p.position, q.position, sizeof p.position) != 0 ||
		    memcmp(p.velocity, q.velocity, sizeof p.velocity) != 0 || strcmp(na, nb) != 0) {
			printf("  particle %d differs\n", (int)i);
			result = 1;
		}
	}
	for (int32_t s = 0; result == 0 && s < sm_model_spring_count(ma); s++) {
		sm_spring_def p, q;
		sm_model_get_spring(ma, s, &p);
		sm_model_get_spring(mb, s, &q);
		double ka[3], kb[3];
		sm_model_spring_constants(ma, s, &ka[0], &ka[1], &ka[2]);
		sm_model_spring_constants(mb, s, &kb[0], &kb[1], &kb[2]);
		if (p.a != q.a || p.b != q.b || p.kind != q.kind || p.section != q.section ||
		    memcmp(ka, kb, sizeof ka) != 0) {
			printf("  spring %d differs\n", (int)s);
			result = 1;
		}
	}
	sm_model_destroy(ma);
	sm_model_destroy(mb);
	return result;
}

static const char square_inline[] =
    "{\"springmass\": 1, \"name\": \"square\", \"structures\": [{\"type\": \"mesh\", \"name\": \"s\", \"density\": 0.3,"
    " \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2], [0, 2, 3]],"
    " \"edge\": {\"section_stiffness\": 200, \"strain_damping\": 0.1}, \"bend\": {\"strain_stiffness\": 2}}],"
    " \"fixed\": [\"s[0]\", \"s[1]\"]}";

// The square as an OBJ file; `file` stands in for the model's "vertices" and "triangles".
static const char square_from_file[] =
    "{\"springmass\": 1, \"name\": \"square\", \"structures\": [{\"type\": \"mesh\", \"name\": \"s\", \"density\": 0.3,"
    " \"file\": \"%s\","
    " \"edge\": {\"section_stiffness\": 200, \"strain_damping\": 0.1}, \"bend\": {\"strain_stiffness\": 2}}],"
    " \"fixed\": [\"s[0]\", \"s[1]\"]}";

static sm_document* load_square(const char* obj_name, const char* obj_text, sm_error* err)
{
	if (write_file(obj_name, obj_text) != 0)
		return NULL;
	char json[1024];
	snprintf(json, sizeof json, square_from_file, obj_name);
	return load_model("square.json", json, err);
}

// A unit square as two triangles, as one quad (cut into the same two triangles, a fan from its first
// vertex), with every form of a face's vertex, relative indices, comments, blank lines, CR LF and
// lone CR line ends, a line continued with a backslash (and one ending the text), form feeds and
// vertical tabs between words, a backslash right after a word, a weight and a colour after a
// vertex (also beyond the largest double: they are dropped), an exponent after E, a number of 64 characters,
// and the statements that carry no geometry: each loads to exactly the inline square's model (masses from the
// areas, springs once per edge, rest lengths, sections).
static int test_obj_square_is_the_inline_square(void)
{
	static const char* const files[] = {
	    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
	    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
	    "# a unit square\r\nmtllib square.mtl\r\no square\r\n\r\nv 0.0 0.0 0.0 1.0\r\nv 1. .0 0e0 0.5 0.5 0.5\r\n"
	    "v +1 1 +0e5\r\nv 0 1 0\r\nvt 0 0\r\nvt 1 0\r\nvn 0 0 1\r\ng front\r\nusemtl cloth\r\ns off\r\n"
	    "f 1/1/1 2/2/1 3/1/1\r\nf 1//1 \\\r\n 3//1 4//1 # the second\r\nl 1 2\r\np 4\r\n",
	    "v 0 0 0\rv 1 0 0\rv 1 1 0\rf -3 -2 -1\rv 0 1 0\rf -4/1 -2/2 -1/3\r",
	    "\xef\xbb\xbf\tv\t0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4",
	    "v 0\f0\v0\nv 1\f0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\n3 4 \\",
	    // A backslash just after a word continues the statement too.
	    "v 0 0 0\nv 1 0 0\nv 1 1\\\n0\nv 0 1 0\nf 1 2 3 4\n",
	    // An exponent after an upper-case E, and a number of 64 characters.
	    "v 0 0 0\nv 1E0 0 0\nv 1 1 0\nv 0 1.00000000000000000000000000000000000000000000000000000000000000 0\nf 1 2 3 4\n",
	    // A weight or a colour is dropped, so only a number: one beyond the largest double is taken.
	    "v 0 0 0 1e999\nv 1 0 0 -1e999 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
	};
	sm_error err = {SM_OK, ""};
	sm_document* inline_square = parse_text(square_inline, &err);
	ENSURE(inline_square != NULL);
	for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
		sm_document* doc = load_square("square.obj", files[k], &err);
		ENSURE(doc != NULL);
		const int same = same_model(inline_square, doc);
		if (same != 0)
			printf("  file %zu\n", k);
		ENSURE(same == 0);
		ENSURE(sm_document_particle_count(doc) == 4);
		// 5 edges (the diagonal once) and one bend spring across the diagonal.
		ENSURE(sm_document_spring_count(doc) == 6);
		ENSURE(strcmp(sm_document_structure_file(doc, 0), "square.obj") == 0);
		sm_document_destroy(doc);
	}
	ENSURE(sm_document_structure_file(inline_square, 0) == NULL);
	ENSURE(sm_document_structure_file(inline_square, 1) == NULL);
	ENSURE(sm_document_structure_file(inline_square, -1) == NULL);
	ENSURE(sm_document_structure_file(NULL, 0) == NULL);
	sm_document_destroy(inline_square);
	return 0;
}

// A hexagonal disc of radius 1 m (a centre and six rim vertices, six triangles around the centre),
// its faces given by negative (relative) indices as each rim vertex is read, is the inline disc; its
// mass is the density times the hexagon's area, 3 sqrt(3) / 2 r^2, the centre taking a third of each
// triangle's share and each rim vertex a third of its two triangles'.
static int test_obj_hexagonal_disc_with_relative_indices(void)
{
	char obj[2048] = "v 0 0 0\n", vertices[1024] = "[0, 0, 0]", triangles[512] = "";
	for (int k = 0; k < 6; k++) {
		const double c = cos(k * M_PI / 3.0), s = sin(k * M_PI / 3.0);
		char line[128];
		// Shortest text that reads back: %.17g.
		snprintf(line, sizeof line, "v %.17g %.17g 0\n", c, s);
		strcat(obj, line);
		snprintf(line, sizeof line, ", [%.17g, %.17g, 0]", c, s);
		strcat(vertices, line);
		if (k > 0) {
			// The centre, the rim vertex before this one, this one, counted back from the last vertex.
			snprintf(line, sizeof line, "f -%d -2 -1\n", k + 2);
			strcat(obj, line);
			snprintf(line, sizeof line, "%s[0, %d, %d]", k > 1 ? ", " : "", k, k + 1);
			strcat(triangles, line);
		}
	}
	// The last triangle closes the disc: the centre, the last rim vertex and the first.
	strcat(obj, "f 1 -1 2\n");
	strcat(triangles, ", [0, 6, 1]");
	char json[4096];
	static const char model[] =
	    "{\"springmass\": 1, \"name\": \"disc\", \"gravity\": [0, 0, 0], \"structures\": [{\"type\": \"mesh\","
	    " \"name\": \"d\", \"density\": 2, %s, \"edge\": {\"strain_stiffness\": 50}, \"bend\": {\"stiffness\": 1}}]}";
	char inline_geometry[2048];
	snprintf(inline_geometry, sizeof inline_geometry, "\"vertices\": [%s], \"triangles\": [%s]", vertices,
	         triangles);
	snprintf(json, sizeof json, model, inline_geometry);
	sm_error err = {SM_OK, ""};
	sm_document* inline_disc = parse_text(json, &err);
	ENSURE(inline_disc != NULL);
	ENSURE(write_file("disc.obj", obj) == 0);
	snprintf(json, sizeof json, model, "\"file\": \"disc.obj\"");
	sm_document* disc = load_model("disc.json", json, &err);
	ENSURE(disc != NULL);
	ENSURE(same_model(inline_disc, disc) == 0);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(disc, &m, NULL), SM_OK);
	// 12 edges (6 spokes, 6 on the rim), 6 interior edges (the spokes) with a bend spring each.
	ENSURE(sm_model_particle_count(m) == 7 && sm_model_spring_count(m) == 18);
	const sm_structure_info info = sm_document_structure(disc, 0);
	ENSURE(info.range.group_spring_count[0] == 12 && info.range.group_spring_count[1] == 6);
	// Masses from areas to rounding: a few ulps of the cosines, sines and cross products.
	ENSURE_REL(sm_model_total_mass(m), 2.0 * 1.5 * sqrt(3.0), 1e-14, 0.0);
	sm_particle_def centre, rim;
	sm_model_get_particle(m, 0, &centre);
	sm_model_get_particle(m, 3, &rim);
	ENSURE_REL(centre.mass, 2.0 * 1.5 * sqrt(3.0) / 3.0, 1e-14, 0.0);
	ENSURE_REL(rim.mass, 2.0 * 2.0 * (sqrt(3.0) / 4.0) / 3.0, 1e-14, 0.0);
	// Every spoke and rim edge is 1 m long at rest (a regular hexagon's side is its radius).
	for (int32_t s = 0; s < 12; s++) {
		double l0, ks, kd;
		sm_model_spring_constants(m, s, &l0, &ks, &kd);
		ENSURE_REL(l0, 1.0, 1e-15, 0.0);
	}
	sm_model_destroy(m);
	sm_document_destroy(disc);
	sm_document_destroy(inline_disc);
	return 0;
}

// "scale" and "origin" put the file's vertex v at origin + scale v, for a mesh read from a file or
// given inline alike; from a parameter, which then feeds the initial state in metres' ratio ("1")
// and changes without the file (read once, when the model was loaded).
static int test_scale_and_origin_place_the_mesh(void)
{
	static const char obj[] = "v 0 0 0\nv 1000 0 0\nv 0 0 500\nf 1 2 3\n";
	static const char model[] =
	    "{\"springmass\": 1, \"name\": \"mm\", \"parameters\": {\"s\": 0.5}, \"structures\": [{\"type\": \"mesh\","
	    " \"name\": \"t\", %s, \"scale\": \"s\", \"origin\": [1, 2, 3], \"edge\": {\"stiffness\": 10}}]}";
	char json[1024];
	ENSURE(write_file("mm.obj", obj) == 0);
	snprintf(json, sizeof json, model, "\"file\": \"mm.obj\"");
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_model("mm.json", json, &err);
	ENSURE(doc != NULL);
	snprintf(json, sizeof json, model,
	         "\"vertices\": [[0, 0, 0], [1000, 0, 0], [0, 0, 500]], \"triangles\": [[0, 1, 2]]");
	sm_document* inline_doc = parse_text(json, &err);
	ENSURE(inline_doc != NULL);
	ENSURE(same_model(doc, inline_doc) == 0);
	ENSURE(sm_document_parameter_uses(doc, 0) == SM_PARAMETER_INITIAL_STATE);
	ENSURE(strcmp(sm_document_parameter_unit(doc, 0), "1") == 0);
	// Exact: halves of whole numbers plus whole numbers.
	static const double expected[2][3][3] = {{{1, 2, 3}, {501, 2, 3}, {1, 2, 253}},
	                                         {{1, 2, 3}, {2001, 2, 3}, {1, 2, 1003}}};
	char path[256];
	snprintf(path, sizeof path, "%s/mm.obj", work);
	ENSURE(remove(path) == 0);
	for (int pass = 0; pass < 2; pass++) {
		if (pass == 1)
			ENSURE_STATUS(sm_document_set_parameter(doc, 0, 2.0, &err), SM_OK);
		sm_model* m = NULL;
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		for (int32_t i = 0; i < 3; i++) {
			sm_particle_def p;
			sm_model_get_particle(m, i, &p);
			ENSURE(p.position[0] == expected[pass][i][0] && p.position[1] == expected[pass][i][1] &&
			       p.position[2] == expected[pass][i][2]);
		}
		double l0, ks, kd;
		sm_model_spring_constants(m, 0, &l0, &ks, &kd);
		ENSURE(l0 == (pass == 0 ? 500.0 : 2000.0));
		sm_model_destroy(m);
	}
	// Without "scale" and "origin" a vertex is the file's own, to the sign of a zero coordinate.
	ENSURE(write_file("zero.obj", "v -0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") == 0);
	sm_document* zero =
	    load_model("zero.json",
		           "{\"springmass\": 1, \"name\": \"z\", \"structures\": [{\"type\": \"mesh\", "
		           "\"name\": \"t\", \"file\": \"zero.obj\", \"edge\": {\"stiffness\": 10}}]}",
		           &err);
	ENSURE(zero != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(zero, &m, NULL), SM_OK);
	sm_particle_def p;
	sm_model_get_particle(m, 0, &p);
	ENSURE(p.position[0] == 0.0 && signbit(p.position[0]));
	sm_model_destroy(m);
	sm_document_destroy(zero);
	// A scale must be > 0.
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 0.0, &err), SM_ERROR_NEGATIVE);
	ENSURE(strstr(err.message, "structures[0].scale: parameter s = 0 must be > 0") != NULL);
	sm_document_destroy(inline_doc);
	sm_document_destroy(doc);
	return 0;
}

// The OBJ file is found relative to the model file's folder (sm_document_load), or to the folder
// given (sm_document_parse_in_folder), or to the current directory (sm_document_parse); an absolute
// path wherever the model is.
static int test_obj_paths(void)
{
	char sub[128], path[4200];
	snprintf(sub, sizeof sub, "%s/meshes", work);
	ENSURE(mkdir(sub, 0755) == 0);
	ENSURE(write_file("meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") == 0);
	static const char model[] = "{\"springmass\": 1, \"name\": \"tri\", \"structures\": [{\"type\": \"mesh\","
	                            " \"name\": \"t\", \"file\": \"%s\"}]}";
	char json[4400];
	sm_error err = {SM_OK, ""};
	snprintf(json, sizeof json, model, "meshes/tri.obj");
	sm_document* doc = load_model("tri.json", json, &err);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 3);
	// The path it was read from: the model file's folder joined to "file", as written.
	snprintf(path, sizeof path, "%s/meshes/tri.obj", work);
	ENSURE(strcmp(sm_document_structure_file(doc, 0), "meshes/tri.obj") == 0);
	ENSURE(strcmp(sm_document_structure_file_path(doc, 0), path) == 0);
	ENSURE(sm_document_structure_file_path(doc, 1) == NULL &&
	       sm_document_structure_file_path(NULL, 0) == NULL);
	sm_document_destroy(doc);
	doc = sm_document_parse_in_folder(json, strlen(json), "tri.json", work, &err);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 3);
	ENSURE(strcmp(sm_document_structure_file_path(doc, 0), path) == 0);
	sm_document_destroy(doc);
	// From text, relative to the current directory: not the work folder's mesh.
	ENSURE(sm_document_parse(json, strlen(json), "tri.json", &err) == NULL);
	ENSURE(strcmp(err.message, "tri.json: structures[0].file: meshes/tri.obj: cannot open: No such file or "
	                           "directory") == 0);
	ENSURE(chdir(work) == 0);
	doc = sm_document_parse(json, strlen(json), "tri.json", &err);
	ENSURE(chdir(home) == 0);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 3);
	ENSURE(strcmp(sm_document_structure_file_path(doc, 0), "meshes/tri.obj") == 0);
	sm_document_destroy(doc);
	// An absolute path, from a model in another folder.
	snprintf(path, sizeof path, "%s/%s/meshes/tri.obj", home, work);
	snprintf(json, sizeof json, model, path);
	doc = load_model("meshes/absolute.json", json, &err);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 3);
	ENSURE(strcmp(sm_document_structure_file_path(doc, 0), path) == 0);
	sm_document_destroy(doc);
	// A model opened through a symbolic link reads relative to the link's folder (meshes/), not to
	// its target's (the work folder), as docs/model-format.md says: meshes/meshes/tri.obj, absent at
	// first, then a square of two triangles whose four particles tell it from the target's mesh.
	snprintf(path, sizeof path, "%s/meshes/link.json", work);
	ENSURE(symlink("../tri.json", path) == 0);
	ENSURE(sm_document_load(path, &err) == NULL);
	ENSURE(strstr(err.message, "/meshes/link.json: structures[0].file: ") != NULL &&
	       strstr(err.message, "/meshes/meshes/tri.obj: cannot open") != NULL);
	snprintf(sub, sizeof sub, "%s/meshes/meshes", work);
	ENSURE(mkdir(sub, 0755) == 0);
	ENSURE(write_file("meshes/meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n") ==
	       0);
	doc = sm_document_load(path, &err);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 4);
	sm_document_destroy(doc);
	return 0;
}

// The canonical form writes the mesh's particles and springs, and the self-contained text its
// vertices and triangles: both load without the OBJ file to the same model, and the self-contained
// text keeps the parameters (a scale), which change it as they change the original. A coordinate
// that needs 17 significant digits (0.30000000000000004, the double after 0.3) keeps them.
static int test_saved_models_need_no_obj_file(void)
{
	static const char obj[] =
	    "v -0.0 0 0\nv 0.1 0 0\nv 0.1 0.30000000000000004 0\nv 0 0.3 1e-300\nf 1 2 3 4\n";
	static const char model[] =
	    "{\"springmass\": 1, \"name\": \"saved\", \"parameters\": {\"s\": 3, \"E\": 40}, \"structures\": [{\"type\":"
	    " \"mesh\", \"name\": \"q\", \"file\": \"saved.obj\", \"scale\": \"s\", \"edge\": {\"strain_stiffness\": \"E\"}}],"
	    " \"ports\": [{\"name\": \"corner\", \"particle\": \"q[2]\", \"kind\": \"force\"}]}";
	ENSURE(write_file("saved.obj", obj) == 0);
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_model("saved.json", model, &err);
	ENSURE(doc != NULL);
	char* canonical = sm_document_to_json(doc, &err);
	char* self_contained = sm_document_to_self_contained_json(doc, &err);
	ENSURE(canonical != NULL && self_contained != NULL);
	ENSURE(strstr(canonical, "saved.obj") == NULL && strstr(self_contained, "saved.obj") == NULL);
	char path[256];
	snprintf(path, sizeof path, "%s/saved.obj", work);
	ENSURE(remove(path) == 0);
	sm_document* again = parse_text(canonical, &err);
	sm_document* whole = parse_text(self_contained, &err);
	ENSURE(again != NULL && whole != NULL);
	ENSURE(same_model(doc, again) == 0 && same_model(doc, whole) == 0);
	ENSURE(sm_document_port(whole, 0).particle == 2 && sm_document_parameter_count(whole) == 2);
	ENSURE(sm_document_structure_file(whole, 0) == NULL);
	// Its text is the same again (a fixed point), and a parameter changes both alike.
	char* twice = sm_document_to_self_contained_json(whole, &err);
	ENSURE(twice != NULL && strcmp(twice, self_contained) == 0);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 0.25, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameter(whole, 0, 0.25, &err), SM_OK);
	ENSURE(same_model(doc, whole) == 0);
	free(twice);
	free(canonical);
	free(self_contained);
	sm_document_destroy(whole);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// The loader's entry with another limit on particles and springs (lib/model_file_internal.h).
sm_document* sm_document_parse_limited(const char* text, size_t length, const char* source_name,
                                       int64_t max_elements, sm_error* err);

// Broken OBJ files and "file" keys: each is refused with exactly its message, which names the OBJ
// file, its line and column (that of the statement's keyword, or of the word at fault) and the
// rule, after the structure's path in the model file. The model is parsed in the work folder, where
// its OBJ files are; `max` limits the model's particles (0: the default).
static int test_broken_obj_files(void)
{
	static const struct {
		const char* obj;   // written as bad.obj; NULL: none
		const char* mesh;  // the mesh's keys after its type and name
		int64_t max;
		sm_status status;
		const char* message;
	} cases[] = {
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:4:7: face index 4 is past the 3 vertices"},
	    {"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:3:9: face index -3 counts back past the first vertex (2 vertices "
		 "come before it)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:4:3: face index 0: vertices are numbered from 1, or back from -1 "
		 "for the last one read"},
	    // An index past any a file may have is named as written (2^63, past a 64-bit integer, here).
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9223372036854775808/1\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:4:7: face index 9223372036854775808 is past the 3 vertices"},
	    // 24 characters, the most shown whole.
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 100000000000000000000000\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:4:7: face index 100000000000000000000000 is past the 3 vertices"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -1000000000000000000000000000000//1\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:4:7: face index -10000000000000000000000... counts back past the "
		 "first vertex (3 vertices come before it)"},
	    {"f 1 2 3\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_PARTICLE_INDEX,
		 "test.json: structures[0].file: bad.obj:1:3: face index 1 is past the 0 vertices"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\n  f 1 2\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:3: a face needs at least 3 vertices, not 2"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2/ 3\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:5: \"2/\" is not a face's vertex (i, i/t, i//n or i/t/n, whole "
		 "numbers)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3//\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:7: \"3//\" is not a face's vertex (i, i/t, i//n or i/t/n, whole "
		 "numbers)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:7: \"3/1/1/1\" is not a face's vertex (i, i/t, i//n or i/t/n, "
		 "whole numbers)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:7: \"3.0\" is not a face's vertex (i, i/t, i//n or i/t/n, whole "
		 "numbers)"},
	    // Columns count characters, a continued statement's words are on their own lines.
	    {"# é\nv 0 0 0\nv 1 0 \\\n  0x1\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:4:3: \"0x1\" is not a number"},
	    {"v 0 0 é\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:7: \"é\" is not a number"},
	    {"v 0 1e 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:5: \"1e\" is not a number"},
	    {"v 0 .e5 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:5: \".e5\" is not a number"},
	    // A byte-order mark takes no column, as an editor shows none.
	    {"\xef\xbb\xbfv 0 0 x\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:7: \"x\" is not a number"},
	    {"v 0 0 inf\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:7: \"inf\" is not a number"},
	    {"v 0 1e999 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_NOT_FINITE,
		 "test.json: structures[0].file: bad.obj:1:5: coordinate \"1e999\" is beyond the largest double"},
	    {"v 0 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:1: a vertex has 3 coordinates x y z, then a weight w or a colour r "
		 "g b at most, not 2 numbers"},
	    {"v 0 0 0 1 1\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:1: a vertex has 3 coordinates x y z, then a weight w or a colour r "
		 "g b at most, not 5 numbers"},
	    {"v 0 0 0 1 1 1 1 1 1\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:1:1: a vertex has 3 coordinates x y z, then a weight w or a colour r "
		 "g b at most, not 7 or more numbers"},
	    {"v 0 0 0\r\nv 1 0 0\r\ncstype bspline\r\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:3:1: \"cstype\": free-form curves and surfaces are not read (export "
		 "the mesh as polygons)"},
	    {"v 0 0 0\rvv 1 0 0\r", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:2:1: unknown statement \"vv\" (a mesh is read from v and f; vt, vn, "
		 "o, g, s, usemtl, mtllib, l and the like are skipped)"},
	    // A statement of 100 bytes, quoted by its first 80: the reason is whole after it.
	    {"v 0 0 0\nxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx 1\n",
		 "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:2:1: unknown statement "
		 "\"xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx\"... "
		 "(a mesh is read from v and f; vt, vn, o, g, s, usemtl, mtllib, l and the like are skipped)"},
	    {"# only points\nv 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0].file: bad.obj: no face (f), so no triangle: a mesh needs at least one"},
	    {"v 0 0 0\nv 1 0 0\n\x00v 0 1 0\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SYNTAX,
		 "test.json: structures[0].file: bad.obj:3:1: a NUL byte (an OBJ file is text)"},
	    // The mesh builder's rules, at the line of the face or vertex at fault.
	    {"v 0 0 0\nv 0.1 0.2 0.3\nv 0.3 0.6 0.9\nv 1 0 0\nf 1 2 4\nf 1 2 3\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0].file: bad.obj:6:1: mesh: triangle 1 (0, 1, 2) has zero area (to rounding: twice "
		 "its area is at most 1e-12 times the product of its two longest edges)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2 1 2\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0].file: bad.obj:5:1: mesh: triangle 1 repeats the vertices of an earlier triangle "
		 "(2, 1, 0)"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\n f 1 2 2\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_SELF_SPRING,
		 "test.json: structures[0].file: bad.obj:4:2: mesh: triangle 0 (0, 1, 1) repeats a vertex"},
	    {"v 0 0 0\nv 1 0 0\n\nf 1 2 1\n", "\"file\": \"bad.obj\"", 0, SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0].file: bad.obj:4:1: mesh: 2 vertices and 1 triangle; a mesh needs at least 3 "
		 "vertices and 1 triangle"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n", "\"file\": \"bad.obj\"",
		 0, SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0].file: bad.obj:8:1: mesh: edge (0, 1) of triangle 2 is shared by more than two "
		 "triangles"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_NONPOSITIVE_MASS,
		 "test.json: structures[0].file: bad.obj:4:1: mesh: vertex 3 belongs to no triangle"},
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\t v 5 5 5\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_NONPOSITIVE_MASS,
		 "test.json: structures[0].file: bad.obj:5:3: mesh: vertex 3 belongs to no triangle"},
	    // The first vertex too: at the line of its v.
	    {"  v 5 5 5\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n", "\"file\": \"bad.obj\"", 0,
		 SM_ERROR_NONPOSITIVE_MASS,
		 "test.json: structures[0].file: bad.obj:1:3: mesh: vertex 0 belongs to no triangle"},
	    {"v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n", "\"file\": \"bad.obj\", \"scale\": \"s\"", 0,
		 SM_ERROR_NOT_FINITE,
		 "test.json: structures[0].file: bad.obj:2:1: mesh: vertex 1 coordinate 0 = inf is not finite (with "
		 "parameter s = 10000000000)"},
	    // The limits: 10 particles, and twice as many triangles.
	    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 0 0\nv 2 1 0\nv 3 0 0\nv 3 1 0\nv 4 0 0\nv 4 1 0\nv 5 0 0\n",
		 "\"file\": \"bad.obj\"", 10, SM_ERROR_SCHEMA,
		 "test.json: structures[0].file: bad.obj:11:1: more than 10 vertices, the most a model's particles allow"},
	    {"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4 1 2\nf 1 2 3\n",
		 "\"file\": \"bad.obj\"", 10, SM_ERROR_SCHEMA,
		 "test.json: structures[0].file: bad.obj:6:1: more than 20 triangles (faces cut into triangles), the most a "
		 "mesh may have"},
	    // The "file" key.
	    {NULL, "\"file\": \"missing.obj\"", 0, SM_ERROR_FILE,
		 "test.json: structures[0].file: missing.obj: cannot open: No such file or directory"},
	    {NULL, "\"file\": \".\"", 0, SM_ERROR_FILE,
		 "test.json: structures[0].file: .: cannot read: Is a directory"},
	    {NULL, "\"file\": \"fifo.obj\"", 0, SM_ERROR_FILE,
		 "test.json: structures[0].file: fifo.obj: cannot read: not a regular file"},
	    {NULL, "\"file\": \"a\\u001b[31m.obj\"", 0, SM_ERROR_FILE,
		 "test.json: structures[0].file: a\\u001b[31m.obj: cannot open: No such file or directory"},
	    {NULL, "\"file\": 3", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0].file: must be a string, the path of an OBJ file, not a number"},
	    {NULL, "\"file\": \"\"", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0].file: must name an OBJ file, not be empty"},
	    {NULL, "\"file\": \"bad.obj\", \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0]: give \"file\" (an OBJ file) or \"vertices\" and \"triangles\", not both"},
	    {NULL, "\"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2]], \"scale\": -1",
		 0, SM_ERROR_NEGATIVE, "test.json: structures[0].scale: -1 must be > 0"},
	    {NULL,
		 "\"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2]], \"origin\": [0, 0]", 0,
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].origin: must be an array of 3 numbers [x, y, z], not an array of "
		 "another length"},
	    {NULL, "\"fil\": \"bad.obj\"", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0]: unknown key \"fil\" (allowed here: type, name, vertices, triangles, file, scale, "
		 "origin, density, edge, bend)"},
	    {NULL, "\"density\": 2", 0, SM_ERROR_SCHEMA,
		 "test.json: structures[0]: missing required key \"vertices\""},
	};
	static const char model[] = "{\"springmass\": 1, \"name\": \"bad\", \"parameters\": {\"s\": 1e10},"
	                            " \"structures\": [{\"type\": \"mesh\", \"name\": \"m\", %s}]}";
	char fifo[128];
	snprintf(fifo, sizeof fifo, "%s/fifo.obj", work);
	ENSURE(mkfifo(fifo, 0600) == 0);
	int failures = 0;
	for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
		if (cases[k].obj != NULL) {
			// The NUL byte's case is written whole: its text goes on after the NUL.
			const size_t n = strstr(cases[k].message, "NUL") != NULL ? 25 : strlen(cases[k].obj);
			char path[128];
			snprintf(path, sizeof path, "%s/bad.obj", work);
			FILE* f = fopen(path, "wb");
			ENSURE(f != NULL && fwrite(cases[k].obj, 1, n, f) == n && fclose(f) == 0);
		}
		char json[1024];
		snprintf(json, sizeof json, model, cases[k].mesh);
		sm_error err = {SM_OK, ""};
		ENSURE(chdir(work) == 0);
		sm_document* doc =
		    cases[k].max > 0 ? sm_document_parse_limited(json, strlen(json), "test.json", cases[k].max, &err)
			                 : sm_document_parse(json, strlen(json), "test.json", &err);
		ENSURE(chdir(home) == 0);
		if (doc != NULL || err.status != cases[k].status || strcmp(err.message, cases[k].message) != 0) {
			printf("  case %zu: status %d, expected %d\n    got      %s\n    expected %s\n", k,
			       (int)err.status, (int)cases[k].status, doc != NULL ? "(loaded)" : err.message,
			       cases[k].message);
			failures++;
		}
		sm_document_destroy(doc);
	}
	ENSURE(remove(fifo) == 0);
	ENSURE(failures == 0);
	// The particles of two meshes of one file count together: 7 vertices each, 14 past a limit of 10.
	// A number longer than the words a line usually holds reads as any other.
	ENSURE(write_file("six.obj",
	                  "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
	                  "f 1 2 3 4\nf 2 5 6 3 # two quads\n"
	                  "v 0.000000000000000000000000000000000000000000000000000000000000000000000001 -1 0\n"
	                  "f 2 1 -1\n") == 0);
	static const char twice[] =
	    "{\"springmass\": 1, \"name\": \"twice\", \"structures\": [{\"type\": \"mesh\","
	    " \"name\": \"a\", \"file\": \"six.obj\"}, {\"type\": \"mesh\", \"name\": \"b\","
	    " \"file\": \"six.obj\", \"origin\": [0, 0, 1]}]}";
	sm_error err = {SM_OK, ""};
	ENSURE(chdir(work) == 0);
	sm_document* doc = sm_document_parse_limited(twice, strlen(twice), "test.json", 14, &err);
	sm_document* over = sm_document_parse_limited(twice, strlen(twice), "test.json", 10, &err);
	ENSURE(chdir(home) == 0);
	if (doc == NULL)
		printf("  %s\n", err.message);
	ENSURE(doc != NULL && sm_document_particle_count(doc) == 14 && over == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: structures[1]: the model would have 14 particles, more than the limit of "
	              "10") == 0);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_particle_def last;
	sm_model_get_particle(m, 6, &last);
	ENSURE(last.position[0] == 1e-72);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	ENSURE(sm_document_to_self_contained_json(NULL, &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);
	return 0;
}

// Writes a polygon of n vertices on the unit circle to `path`, as one face of n corners after
// `blanks` blanks on its line; false if it cannot. Returns the file's length in *length.
static bool write_polygon(const char* path, int n, int blanks, size_t* length)
{
	const size_t capacity = 64 * (size_t)n + (size_t)blanks;
	char* obj = malloc(capacity);
	if (obj == NULL)
		return false;
	size_t used = 0;
	for (int k = 0; k < n; k++)
		used += (size_t)snprintf(obj + used, capacity - used, "v %.17g %.17g 0\n", cos(2 * M_PI * k / n),
		                         sin(2 * M_PI * k / n));
	memset(obj + used, ' ', (size_t)blanks);
	used += (size_t)blanks;
	used += (size_t)snprintf(obj + used, capacity - used, "f");
	for (int k = 0; k < n; k++)
		used += (size_t)snprintf(obj + used, capacity - used, " %d", k + 1);
	snprintf(obj + used, capacity - used, "\n");
	*length = strlen(obj);
	const bool written = write_file(path, obj) == 0;
	free(obj);
	return written;
}

// A model of one mesh, p, read from the OBJ file `obj`.
static sm_document* load_mesh_of(const char* obj, sm_error* err)
{
	char text[256];
	snprintf(text, sizeof text,
	         "{\"springmass\": 1, \"name\": \"m\", \"structures\": [{\"type\": \"mesh\", \"name\": \"p\","
	         " \"file\": \"%s\", \"edge\": {\"stiffness\": 1}}]}",
	         obj);
	return load_model("mesh.json", text, err);
}

// A hostile face of many vertices within the limits: cut into one triangle per vertex past the
// second, a fan whose triangles all share the fan's first vertex; a sliver-free fan over a circle
// loads.
static int test_polygon_of_many_vertices_is_a_fan(void)
{
	enum { N = 2000 };
	size_t length = 0;
	ENSURE(write_polygon("polygon.obj", N, 0, &length));
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_mesh_of("polygon.obj", &err);
	ENSURE(doc != NULL);
	// N - 2 triangles: N rim edges and N - 3 diagonals from the first vertex.
	ENSURE(sm_document_particle_count(doc) == N && sm_document_spring_count(doc) == 2 * N - 3);
	sm_document_destroy(doc);
	return 0;
}

// The bytes the library has read to find columns (sm_text_column, wrapped by the linker: see
// tests/CMakeLists.txt).
static size_t column_bytes = 0;

int64_t __real_sm_text_column(const char* line, size_t bytes);
int64_t __wrap_sm_text_column(const char* line, size_t bytes);

int64_t __wrap_sm_text_column(const char* line, size_t bytes)
{
	column_bytes += bytes;
	return __real_sm_text_column(line, bytes);
}

// A face of many vertices after a long run of blanks (as a hostile file may write it): the line
// is read for the columns of its triangles once, not once per triangle, so that loading takes
// time in proportion to the file. Read once per triangle, the 4000 triangles would read the
// 100 000 blanks 4000 times: 4e8 bytes where the file has 1.6e5.
static int test_face_after_many_blanks_reads_its_line_once(void)
{
	enum { N = 4002, BLANKS = 100000 };
	size_t length = 0;
	ENSURE(write_polygon("blanks.obj", N, BLANKS, &length));
	sm_error err = {SM_OK, ""};
	column_bytes = 0;
	sm_document* doc = load_mesh_of("blanks.obj", &err);
	ENSURE(doc != NULL);
	ENSURE(sm_document_particle_count(doc) == N && sm_document_spring_count(doc) == 2 * N - 3);
	sm_document_destroy(doc);
	// Each statement's line read up to its keyword once, for the places of what it makes.
	printf("  %zu bytes read for columns, file of %zu bytes\n", column_bytes, length);
	ENSURE(column_bytes <= length);
	return 0;
}

static int remove_entry(const char* path, const struct stat* st, int type, struct FTW* walk)
{
	(void)st;
	(void)type;
	(void)walk;
	return remove(path);
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	if (getcwd(home, sizeof home) == NULL)
		return 1;
	strcpy(work, "test_mesh_file_XXXXXX");
	if (mkdtemp(work) == NULL) {
		printf("cannot create a work folder\n");
		return 1;
	}
	RUN_TEST(test_obj_square_is_the_inline_square);
	RUN_TEST(test_obj_hexagonal_disc_with_relative_indices);
	RUN_TEST(test_scale_and_origin_place_the_mesh);
	RUN_TEST(test_obj_paths);
	RUN_TEST(test_saved_models_need_no_obj_file);
	RUN_TEST(test_broken_obj_files);
	RUN_TEST(test_polygon_of_many_vertices_is_a_fan);
	RUN_TEST(test_face_after_many_blanks_reads_its_line_once);
	if (nftw(work, remove_entry, 16, FTW_DEPTH | FTW_PHYS) != 0)
		printf("could not remove %s\n", work);
	return TEST_SUMMARY();
}

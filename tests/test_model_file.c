// Model files: every bundled model loads and has the physics its description promises, saving
// and loading gives the same model, parameters feed the constants, and a table of broken and
// hostile files gives exactly the expected errors.
#define _POSIX_C_SOURCE 200809L  // mkfifo, alarm

#include "springmass/analysis.h"
#include "springmass/model_file.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"
#include "test_harness.h"

#include <dirent.h>
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef SPRINGMASS_MODELS_DIR
#error "SPRINGMASS_MODELS_DIR must name the directory of the bundled models"
#endif

static const char* const bundled[] = {"oscillator", "two_mass_chain", "hanging_rope",
                                      "cloth",      "tearing_cloth",  "jelly_block",
                                      "flag",       "trampoline",     "shade_sail"};
enum { BUNDLED_COUNT = sizeof bundled / sizeof bundled[0] };

static sm_document* load_bundled(const char* name, sm_error* err)
{
	char path[512];
	snprintf(path, sizeof path, "%s/%s.json", SPRINGMASS_MODELS_DIR, name);
	return sm_document_load(path, err);
}

static sm_document* parse(const char* text, sm_error* err)
{
	return sm_document_parse(text, strlen(text), "test.json", err);
}

// parse for a text that must load: prints the message when it does not.
static sm_document* parse_valid(const char* text, sm_error* err)
{
	sm_document* doc = parse(text, err);
	if (doc == NULL)
		printf("  %s\n", err->message);
	return doc;
}

static int32_t count_fixed(const sm_model* m)
{
	int32_t fixed = 0;
	for (int32_t i = 0; i < sm_model_particle_count(m); i++) {
		sm_particle_def p;
		sm_model_get_particle(m, i, &p);
		fixed += p.motion == SM_PARTICLE_FIXED;
	}
	return fixed;
}

// Two models are the same: particles (mass, position, velocity, motion, load), springs (ends, kind,
// scaling, constants as given and as resolved, break strain), gravity and mass damping; all
// bit for bit, since saving writes numbers that read back exactly.
static int same_model(const sm_model* a, const sm_model* b)
{
	ENSURE(sm_model_particle_count(a) == sm_model_particle_count(b));
	ENSURE(sm_model_spring_count(a) == sm_model_spring_count(b));
	for (int32_t i = 0; i < sm_model_particle_count(a); i++) {
		sm_particle_def p, q;
		sm_model_get_particle(a, i, &p);
		sm_model_get_particle(b, i, &q);
		ENSURE(p.mass == q.mass && p.motion == q.motion);
		// Bit for bit: a zero's sign too.
		ENSURE(memcmp(p.position, q.position, sizeof p.position) == 0);
		ENSURE(memcmp(p.velocity, q.velocity, sizeof p.velocity) == 0);
		ENSURE(memcmp(p.load, q.load, sizeof p.load) == 0);
	}
	for (int32_t s = 0; s < sm_model_spring_count(a); s++) {
		sm_spring_def p, q;
		sm_model_get_spring(a, s, &p);
		sm_model_get_spring(b, s, &q);
		ENSURE(p.a == q.a && p.b == q.b && p.kind == q.kind);
		ENSURE(p.stiffness == q.stiffness && p.stiffness_scaling == q.stiffness_scaling);
		ENSURE(p.damping == q.damping && p.damping_scaling == q.damping_scaling);
		ENSURE(p.section == q.section);
		ENSURE(p.rest_length == q.rest_length);
		ENSURE(p.break_strain == q.break_strain || (isinf(p.break_strain) && isinf(q.break_strain)));
		double l0a, ksa, kda, l0b, ksb, kdb;
		sm_model_spring_constants(a, s, &l0a, &ksa, &kda);
		sm_model_spring_constants(b, s, &l0b, &ksb, &kdb);
		ENSURE(l0a == l0b && ksa == ksb && kda == kdb);
	}
	const sm_model_def da = sm_model_get_def(a), db = sm_model_get_def(b);
	ENSURE(memcmp(da.gravity, db.gravity, sizeof da.gravity) == 0);
	ENSURE(da.mass_damping == db.mass_damping);
	return 0;
}

static int same_document(const sm_document* a, const sm_document* b)
{
	ENSURE(strcmp(sm_document_name(a), sm_document_name(b)) == 0);
	ENSURE(strcmp(sm_document_description(a), sm_document_description(b)) == 0);
	// b may be a's canonical form, which lists only the parameters it names, in a's order.
	ENSURE(sm_document_parameter_count(b) <= sm_document_parameter_count(a));
	for (int32_t k = 0, previous = -1; k < sm_document_parameter_count(b); k++) {
		const int32_t in_a = sm_document_parameter_index(a, sm_document_parameter_name(b, k));
		ENSURE(in_a > previous);
		ENSURE(sm_document_parameter_value(a, in_a) == sm_document_parameter_value(b, k));
		previous = in_a;
	}
	ENSURE(sm_document_port_count(a) == sm_document_port_count(b));
	for (int32_t k = 0; k < sm_document_port_count(a); k++) {
		const sm_port p = sm_document_port(a, k), q = sm_document_port(b, k);
		ENSURE(strcmp(p.name, q.name) == 0 && p.particle == q.particle && p.kind == q.kind);
	}
	sm_model *ma = NULL, *mb = NULL;
	ENSURE_STATUS(sm_document_build(a, &ma, NULL), SM_OK);
	ENSURE_STATUS(sm_document_build(b, &mb, NULL), SM_OK);
	const int result = same_model(ma, mb);
	sm_model_destroy(ma);
	sm_model_destroy(mb);
	ENSURE(result == 0);
	for (int32_t i = 0; i < sm_document_port_count(a); i++) {
		const char* na = sm_document_particle_name(a, sm_document_port(a, i).particle);
		const char* nb = sm_document_particle_name(b, sm_document_port(b, i).particle);
		ENSURE((na == NULL && nb == NULL) || (na && nb && strcmp(na, nb) == 0));
	}
	const sm_document_settings sa = sm_document_get_settings(a), sb = sm_document_get_settings(b);
	ENSURE(memcmp(&sa, &sb, sizeof sa) == 0);
	return 0;
}

// Every bundled model loads, has a one-line description, builds, and its canonical form loads
// to the same model; saving that again gives the same text (the canonical form is a fixed point).
static int test_bundled_models_round_trip(void)
{
	for (int k = 0; k < BUNDLED_COUNT; k++) {
		sm_error err = {SM_OK, ""};
		sm_document* doc = load_bundled(bundled[k], &err);
		if (doc == NULL) {
			printf("  %s: %s\n", bundled[k], err.message);
			return 1;
		}
		ENSURE(strcmp(sm_document_name(doc), bundled[k]) == 0);
		ENSURE(strlen(sm_document_description(doc)) > 20);
		char* text = sm_document_to_json(doc, &err);
		ENSURE(text != NULL);
		sm_document* again = sm_document_parse(text, strlen(text), "saved.json", &err);
		if (again == NULL) {
			printf("  %s saved: %s\n", bundled[k], err.message);
			return 1;
		}
		const int same = same_document(doc, again);
		char* text2 = sm_document_to_json(again, &err);
		ENSURE(text2 != NULL);
		const int fixed_point = strcmp(text, text2) == 0;
		free(text);
		free(text2);
		sm_document_destroy(again);
		sm_document_destroy(doc);
		if (same != 0 || !fixed_point) {
			printf("  %s: round trip differs%s\n", bundled[k], fixed_point ? "" : " (text)");
			return 1;
		}
	}
	return 0;
}

// The oscillator's spring and mass give the closed-form frequency sqrt(k/m), and the model's
// force on the bob is -k (x - l0) - d v along the spring (checked at a displaced state).
static int test_oscillator(void)
{
	sm_document* doc = load_bundled("oscillator", NULL);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 2 && sm_model_spring_count(m) == 1);
	ENSURE(sm_document_port_count(doc) == 1);
	const sm_port port = sm_document_port(doc, 0);
	ENSURE(port.kind == SM_PORT_FORCE && strcmp(sm_document_particle_name(doc, port.particle), "bob") == 0);
	const double x[6] = {0, 0, 0, 0.7, 0, 0}, v[6] = {0, 0, 0, 0.3, 0, 0};
	double f[6];
	sm_model_forces(m, x, v, NULL, f);
	// k = 40 N/m, l0 = 0.5 m, d = 0.4 N s/m: f = -40 * 0.2 - 0.4 * 0.3 = -8.12 N (exact in
	// binary to rounding of the products).
	ENSURE_NEAR(f[3], -8.12, 1e-12);
	ENSURE_NEAR(f[0], 8.12, 1e-12);
	const sm_model_def def = sm_model_get_def(m);
	ENSURE(def.gravity[0] == 0.0 && def.gravity[1] == 0.0 && def.gravity[2] == 0.0);
	const sm_document_settings settings = sm_document_get_settings(doc);
	ENSURE(settings.stop_time == 5.0 && settings.solver.relative_tolerance == 1e-8);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// The bundled cloth is exactly the default sheet (the benchmark cloth, n = 16) with its two
// corners at y = 1 fixed, and the benchmark cloth of any n with --set n=N; its probe "center" is
// at cloth[n/2, n/2].
static int test_cloth_is_the_benchmark_cloth(void)
{
	sm_document* doc = load_bundled("cloth", NULL);
	ENSURE(doc != NULL);
	static const int sizes[] = {16, 9, 32};
	for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
		const int n = sizes[k];
		ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), n, NULL), SM_OK);
		sm_model* m = NULL;
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		sm_model_def md = sm_default_model_def();
		sm_model* reference = sm_model_create(&md, NULL);
		sm_sheet_def sheet = sm_default_sheet_def();
		ENSURE(sheet.nu == 16 && sheet.nv == 16);
		sheet.nu = sheet.nv = n;
		sm_structure s;
		ENSURE_STATUS(sm_add_sheet(reference, &sheet, &s), SM_OK);
		ENSURE_STATUS(sm_set_motion_at(reference, &s, n - 1, 0, 0, SM_PARTICLE_FIXED), SM_OK);
		ENSURE_STATUS(sm_set_motion_at(reference, &s, n - 1, n - 1, 0, SM_PARTICLE_FIXED), SM_OK);
		ENSURE(same_model(m, reference) == 0);
		ENSURE(count_fixed(m) == 2);
		ENSURE(sm_document_port(doc, sm_document_port_index(doc, "center")).particle == (n / 2) * n + n / 2);
		sm_model_destroy(reference);
		sm_model_destroy(m);
	}
	ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), 16, NULL), SM_OK);
	ENSURE(strcmp(sm_document_particle_name(doc, 15 * 16 + 3), "cloth[15,3]") == 0);
	ENSURE(sm_document_particle_index(doc, "cloth[2,7]") == 2 * 16 + 7);
	sm_document_destroy(doc);
	return 0;
}

// Facts of the other bundled models that their descriptions state.
static int test_bundled_model_facts(void)
{
	sm_model* m = NULL;
	// Flag: mass lumped from the triangles, density x area = 0.2 kg/m^2 x 1.5 m^2; the pole's
	// five vertices fixed.
	sm_document* doc = load_bundled("flag", NULL);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE_NEAR(sm_model_total_mass(m), 0.2 * 1.5, 1e-12);
	ENSURE(sm_model_particle_count(m) == 35 && count_fixed(m) == 5);
	// 7 x 5 grid, two triangles per cell: 6*5 + 7*4 + 24 = 82 edges; interior edges: all but
	// the 2*6 + 2*4 = 20 boundary ones, 62 bending springs.
	ENSURE(sm_model_spring_count(m) == 82 + 62);
	sm_model_destroy(m);
	sm_document_destroy(doc);

	// Shade sail: the disc of its OBJ file (radius 1 m: a centre vertex, 5 rings of 16) scaled by
	// its parameter scale to a radius r of 1.5 m, with its centre at the origin, (0, 0, 2.5) m; its
	// mass density x the area of the 16-gon, 8 r^2 sin(pi / 8). The file writes 6 decimals: the
	// area within 1e-5 of it.
	doc = load_bundled("shade_sail", NULL);
	ENSURE(doc != NULL);
	const int32_t scale = sm_document_parameter_index(doc, "scale");
	for (int k = 0; k < 2; k++) {
		const double r = k == 0 ? 1.5 : 3.0;
		ENSURE_STATUS(sm_document_set_parameter(doc, scale, r, NULL), SM_OK);
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE(sm_model_particle_count(m) == 81 && count_fixed(m) == 4);
		ENSURE_NEAR(sm_model_total_mass(m), 0.25 * 8.0 * r * r * sin(acos(-1.0) / 8.0),
		            1e-5 * sm_model_total_mass(m));
		// Euler's formula for a disc: 81 vertices + 144 triangles (16 + 2 x 64) - 1 = 224 edges, all
		// but the 16 of the rim between two triangles (208 bend springs).
		ENSURE(sm_model_spring_count(m) == 224 + 208);
		sm_particle_def centre, post;
		sm_model_get_particle(m, 0, &centre);
		ENSURE(centre.position[0] == 0.0 && centre.position[1] == 0.0 && centre.position[2] == 2.5);
		// The posts: the rim's vertices on the axes, at the radius.
		static const char* const posts[] = {"sail[65]", "sail[69]", "sail[73]", "sail[77]"};
		for (int p = 0; p < 4; p++) {
			sm_model_get_particle(m, sm_document_particle_index(doc, posts[p]), &post);
			ENSURE(post.motion == SM_PARTICLE_FIXED && post.position[2] == 2.5);
			ENSURE(fabs(post.position[0]) + fabs(post.position[1]) == r);
		}
		sm_model_destroy(m);
	}
	ENSURE_STATUS(sm_document_set_parameter(doc, scale, 1.5, NULL), SM_OK);
	// At rest the sail hangs below its posts and each post holds a quarter of its weight: the mesh
	// turned by 90 degrees is the same mesh (the file's coordinates are signs of the same rounded
	// numbers), so the four reactions are equal to rounding (1e-9 of the weight).
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	{
		const int32_t n = sm_model_particle_count(m);
		double* x = malloc(3 * (size_t)n * sizeof(double));
		double* reactions = malloc(3 * (size_t)n * sizeof(double));
		ENSURE(x != NULL && reactions != NULL);
		ENSURE_STATUS(sm_statics_solve(m, NULL, x, reactions, NULL, NULL), SM_OK);
		const double weight = 9.81 * sm_model_total_mass(m);
		for (int32_t post = 65; post < 81; post += 4)
			ENSURE_NEAR(reactions[3 * post + 2], weight / 4.0, 1e-9 * weight);
		for (int32_t i = 0; i < n; i++) {
			sm_particle_def p;
			sm_model_get_particle(m, i, &p);
			ENSURE(p.motion == SM_PARTICLE_FIXED || x[3 * i + 2] < 2.5);
		}
		free(x);
		free(reactions);
	}
	sm_model_destroy(m);
	sm_document_destroy(doc);

	// Jelly block: 125 particles on four pins.
	doc = load_bundled("jelly_block", NULL);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 125 && count_fixed(m) == 4);
	ENSURE_NEAR(sm_model_total_mass(m), 1.0, 1e-12);
	sm_model_destroy(m);
	sm_document_destroy(doc);

	// Tearing cloth: every structural and shear spring of the sheet can break, the hook cannot.
	doc = load_bundled("tearing_cloth", NULL);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	int breakable = 0;
	for (int32_t s = 0; s < sm_model_spring_count(m); s++) {
		sm_spring_def def;
		sm_model_get_spring(m, s, &def);
		breakable += isfinite(def.break_strain);
	}
	// 12 x 12: structural 2*11*12 = 264, shear 2*11*11 = 242.
	ENSURE(breakable == 264 + 242);
	ENSURE(count_fixed(m) == 12);
	sm_model_destroy(m);
	sm_document_destroy(doc);

	// Trampoline: a finer grid gives the same membrane. Its centre sags 20.36 mm at rest with the
	// file's 13 x 13 particles and 20.30 mm with 25 x 25 (per-section springs, lumped masses;
	// per strain the finer one would sag half as much): within 0.5 %.
	doc = load_bundled("trampoline", NULL);
	ENSURE(doc != NULL);
	double sag[2];
	for (int k = 0; k < 2; k++) {
		const int32_t n = k == 0 ? 13 : 25;
		ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), n, NULL), SM_OK);
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE_NEAR(sm_model_total_mass(m), 2.0, 1e-12);
		ENSURE(count_fixed(m) == 4 * (n - 1));
		double* x = malloc(3 * (size_t)n * (size_t)n * sizeof(double));
		ENSURE(x != NULL);
		ENSURE_STATUS(sm_statics_solve(m, NULL, x, NULL, NULL, NULL), SM_OK);
		// The force port, membrane[n/2, n/2], follows the grid to its centre.
		const int32_t centre = sm_document_port(doc, sm_document_port_index(doc, "centre")).particle;
		ENSURE(centre == (n / 2) * n + n / 2);
		sag[k] = -x[3 * centre + 2];
		free(x);
		sm_model_destroy(m);
	}
	ENSURE(sag[0] > 0.02 && fabs(sag[1] - sag[0]) < 0.005 * sag[0]);
	// Only the edges are held at any resolution: the boxes that hold them are thinner than a
	// cell of the finest grid the docs use (257 x 257, 3.9 mm; boxes of 1 cm held two rows from
	// 102 x 102 on).
	for (int32_t n = 101; n <= 257; n += 52) {
		ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), n, NULL), SM_OK);
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE(count_fixed(m) == 4 * (n - 1));
		sm_model_destroy(m);
	}
	sm_document_destroy(doc);

	// Hanging rope: pinned at its first particle, 21 particles of 0.5 kg / 21.
	doc = load_bundled("hanging_rope", NULL);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 21 && sm_model_spring_count(m) == 20 && count_fixed(m) == 1);
	ENSURE_NEAR(sm_model_get_def(m).mass_damping, 0.1, 0.0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// The oscillator's description promises a closed form: x(t) = l0 + A e^(-g t) (cos(wd t) +
// g / wd sin(wd t)) with g = d / (2 m), wd = sqrt(k / m - g^2), A = 0.1 m, simulated with the
// file's own settings (rtol 1e-8).
static int test_oscillator_follows_its_closed_form(void)
{
	sm_document* doc = load_bundled("oscillator", NULL);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	const sm_document_settings settings = sm_document_get_settings(doc);
	sm_error err = {SM_OK, ""};
	sm_simulation* sim = sm_simulation_create(m, &settings.solver, &err);
	ENSURE(sim != NULL);
	const double g = 0.4 / 2.0, wd = sqrt(40.0 - g * g);
	double worst = 0.0;
	for (int k = 1; k <= 50; k++) {
		const double t = 0.05 * k;
		ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
		const double exact = 0.5 + 0.1 * exp(-g * t) * (cos(wd * t) + g / wd * sin(wd * t));
		worst = worst_of(worst, fabs(sm_simulation_positions(sim)[3] - exact));
	}
	// rtol 1e-8 and atol 1e-10 m on a 0.5 m position: a global error of a few 1e-8 m over 2.5 s;
	// 1e-6 m leaves a factor of ten for error growth.
	ENSURE(worst < 1e-6);
	sm_simulation_destroy(sim);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// The tearing cloth tears: springs break within the first 0.3 s, all of them springs of the
// sheet that carry a break strain, never the weight's hooks.
static int test_tearing_cloth_tears(void)
{
	sm_document* doc = load_bundled("tearing_cloth", NULL);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	const sm_document_settings settings = sm_document_get_settings(doc);
	sm_error err = {SM_OK, ""};
	sm_simulation* sim = sm_simulation_create(m, &settings.solver, &err);
	ENSURE(sim != NULL);
	ENSURE_STATUS(sm_simulation_advance(sim, 0.3), SM_OK);
	const int32_t breaks = sm_simulation_break_count(sim);
	ENSURE(breaks >= 3);
	for (int32_t k = 0; k < breaks; k++) {
		const sm_break_event e = sm_simulation_break(sim, k);
		sm_spring_def def;
		sm_model_get_spring(m, e.spring, &def);
		ENSURE(isfinite(def.break_strain));
		ENSURE(e.time > 0.0 && e.time <= 0.3);
	}
	sm_simulation_destroy(sim);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A parameter feeds every value that names it; an invalid value is refused with the path of
// the element it breaks, and the document stays as it was.
static int test_parameters(void)
{
	sm_document* doc = load_bundled("cloth", NULL);
	ENSURE(doc != NULL);
	const int32_t E = sm_document_parameter_index(doc, "E");
	ENSURE(E >= 0 && sm_document_parameter_value(doc, E) == 1000.0);
	ENSURE(sm_document_parameter_index(doc, "nothing") == -1);
	ENSURE_STATUS(sm_document_set_parameter(doc, E, 2000.0, NULL), SM_OK);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	double l0, ks;
	sm_model_spring_constants(m, 0, &l0, &ks, NULL);
	ENSURE_REL(ks, 2000.0 / l0, 1e-15, 0.0);
	sm_model_destroy(m);

	sm_error err = {SM_OK, ""};
	ENSURE_STATUS(sm_document_set_parameter(doc, E, -1.0, &err), SM_ERROR_NEGATIVE);
	ENSURE(strstr(err.message,
	              "cloth.json: structures[0].structural.strain_stiffness: parameter E = -1 must be >= 0") !=
	       NULL);
	ENSURE(strstr(err.message, "(with parameter") == NULL);  // the parameter is named once
	ENSURE_STATUS(sm_document_set_parameter(doc, E, NAN, &err), SM_ERROR_NOT_FINITE);
	ENSURE(sm_document_parameter_value(doc, E) == 2000.0);
	ENSURE_STATUS(sm_document_set_parameter(doc, 99, 1.0, &err), SM_ERROR_NOT_FOUND);
	sm_document_destroy(doc);

	// A parameter may set a count: the topology follows it.
	const char* text =
	    "{\"springmass\": 1, \"name\": \"r\", \"parameters\": {\"n\": 4},"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"rope\", \"start\": [0,0,0],"
	    " \"end\": [1,0,0], \"segments\": \"n\", \"structural\": {\"strain_stiffness\": 10}}]}";
	doc = parse(text, &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 9.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 10 && sm_model_spring_count(m) == 9);
	ENSURE(strcmp(sm_document_particle_name(doc, 9), "rope[9]") == 0);
	sm_model_destroy(m);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 2.5, &err), SM_ERROR_SCHEMA);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0].segments: parameter n = 2.5 must be a whole number from 1 to "
	              "4194304") == 0);
	sm_document_destroy(doc);

	// A group whose constants are parameters keeps its springs when they are all zero, so that
	// parameters never change the topology (an FMU's tunable parameters); literal zeros make
	// no springs. 4 x 3 sheet: 17 structural, 12 shear, 10 bend springs.
	text = "{\"springmass\": 1, \"name\": \"s\", \"parameters\": {\"E\": 0, \"c\": 0},"
	       " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"nu\": 4, \"nv\": 3,"
	       " \"structural\": {\"strain_stiffness\": 100}, \"shear\": {\"strain_stiffness\": \"E\","
	       " \"strain_damping\": \"c\"}, \"bend\": {\"strain_stiffness\": 0}}]}";
	doc = parse(text, &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_spring_count(m) == 17 + 12);
	sm_model_destroy(m);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 50.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_spring_count(m) == 17 + 12);
	sm_spring_def shear;  // particle 0's springs: to (0, 1) and (1, 0) structural, to (1, 1) shear
	ENSURE_STATUS(sm_model_get_spring(m, 2, &shear), SM_OK);
	ENSURE(shear.a == 0 && shear.b == 5);
	sm_model_spring_constants(m, 2, &l0, &ks, NULL);
	ENSURE_REL(ks, 50.0 / l0, 1e-15, 0.0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// What each parameter feeds, from the places the file names it: one parameter per kind of place
// (a particle's mass and position, a spring's constants, a rope's ends, count and mass, a mesh's
// vertices and triangles, a box of held particles, the settings, gravity, the rest length of a
// spring with and without a kind), one in two kinds, one unused; the uses stay when a value
// changes the counts.
static int test_parameter_uses(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"u\", \"parameters\": {\"m\": 1, \"x\": 0, \"k\": 5, \"c\": 0.1,"
	    " \"L\": 1, \"n\": 4, \"M\": 2, \"v\": 0, \"i\": 2, \"b\": 0.5, \"tol\": 1e-6, \"g\": -9.81, \"both\": 2,"
	    " \"spare\": 3, \"l0\": 0.5, \"l1\": 0.5},"
	    " \"gravity\": [0, 0, \"g\"],"
	    " \"particles\": [{\"name\": \"p\", \"position\": [\"x\", 0, 5], \"mass\": \"m\"},"
	    "                 {\"name\": \"q\", \"position\": [1, 0, 5], \"mass\": \"both\"}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": \"q\", \"stiffness\": \"k\", \"damping\": \"c\"},"
	    "             {\"a\": \"p\", \"b\": \"q\", \"rest_length\": \"l0\", \"stiffness\": 1},"
	    "             {\"a\": \"p\", \"b\": \"q\", \"kind\": \"rest_length\", \"rest_length\": \"l1\", \"stiffness\": 1}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [\"L\", 0, 0],"
	    "   \"segments\": \"n\", \"mass\": \"M\", \"structural\": {\"strain_stiffness\": 10}},"
	    "  {\"type\": \"mesh\", \"name\": \"t\", \"density\": 1, \"vertices\": [[0, 0, 2], [1, 0, 2], [0, \"both\", \"v\"]],"
	    "   \"triangles\": [[0, 1, \"i\"]], \"edge\": {\"strain_stiffness\": 10}}],"
	    " \"fixed\": [\"r[0]\", {\"min\": [-1, -1, -1], \"max\": [\"b\", 0.1, 0.1]}],"
	    " \"simulation\": {\"rtol\": \"tol\"}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const struct {
		const char* name;
		uint32_t uses;
	} expected[] = {
	    {"m", SM_PARAMETER_CONSTANTS},
	    {"x", SM_PARAMETER_INITIAL_STATE},
	    {"k", SM_PARAMETER_CONSTANTS},
	    {"c", SM_PARAMETER_CONSTANTS},
	    {"L", SM_PARAMETER_INITIAL_STATE},
	    {"n", SM_PARAMETER_COUNTS},
	    {"M", SM_PARAMETER_CONSTANTS},
	    {"v", SM_PARAMETER_INITIAL_STATE},
	    {"i", SM_PARAMETER_COUNTS},
	    {"b", SM_PARAMETER_MOTION},
	    {"tol", SM_PARAMETER_SETTINGS},
	    {"g", SM_PARAMETER_CONSTANTS},
	    {"both", SM_PARAMETER_CONSTANTS | SM_PARAMETER_INITIAL_STATE},
	    {"spare", 0},
	    // Without a kind, a rest length of 0 makes the spring zero-length: it chooses the law.
	    {"l0", SM_PARAMETER_CONSTANTS | SM_PARAMETER_SPRING_KINDS},
	    {"l1", SM_PARAMETER_CONSTANTS},
	};
	for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++) {
		const int32_t k = sm_document_parameter_index(doc, expected[e].name);
		ENSURE(k >= 0);
		if (sm_document_parameter_uses(doc, k) != expected[e].uses)
			printf("  parameter %s: uses %u, expected %u\n", expected[e].name,
			       (unsigned)sm_document_parameter_uses(doc, k), (unsigned)expected[e].uses);
		ENSURE(sm_document_parameter_uses(doc, k) == expected[e].uses);
	}
	ENSURE(sm_document_parameter_uses(doc, -1) == 0 && sm_document_parameter_uses(doc, 99) == 0);
	ENSURE(sm_document_parameter_uses(NULL, 0) == 0);
	const int32_t n = sm_document_parameter_index(doc, "n"), L = sm_document_parameter_index(doc, "L");
	ENSURE_STATUS(sm_document_set_parameter(doc, n, 9.0, &err), SM_OK);
	ENSURE(sm_document_parameter_uses(doc, n) == SM_PARAMETER_COUNTS);
	ENSURE(sm_document_parameter_uses(doc, L) == SM_PARAMETER_INITIAL_STATE);
	sm_document_destroy(doc);
	return 0;
}

// The terms of the potential energy each particle's position enters for some values of the
// parameters: gravity's and the loads' components that are parameters or numbers other than 0, and
// the springs whose stiffness is (a parameter at 0 included, a number 0 not: a damper alone).
static int test_potential_terms(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"t\", \"parameters\": {\"gy\": 0, \"fx\": 0, \"kd\": 0, \"E\": 0},"
	    " \"gravity\": [0, \"gy\", -9.81],"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]}, {\"name\": \"b\", \"position\": [1, 0, 0]},"
	    "   {\"name\": \"c\", \"position\": [2, 0, 0]}, {\"name\": \"d\", \"position\": [3, 0, 0]},"
	    "   {\"name\": \"e\", \"position\": [4, 0, 0]}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 40},"
	    "   {\"a\": \"b\", \"b\": \"c\", \"damping\": 0.3}, {\"a\": \"d\", \"b\": \"e\", \"stiffness\": \"kd\"}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 1, 0], \"end\": [1, 1, 0],"
	    "   \"segments\": 2, \"structural\": {\"strain_stiffness\": \"E\"}},"
	    "  {\"type\": \"rope\", \"name\": \"s\", \"start\": [0, 2, 0], \"end\": [1, 2, 0],"
	    "   \"segments\": 2, \"structural\": {\"strain_stiffness\": 0, \"strain_damping\": 0.1}}],"
	    " \"loads\": [{\"particle\": \"c\", \"force\": [2, 0, 0]}, {\"particle\": \"d\", \"force\": [\"fx\", 0, 0]},"
	    "   {\"particle\": \"e\", \"force\": [0, 0, 0]}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const uint8_t weight = SM_POTENTIAL_CONSTANT_Y | SM_POTENTIAL_CONSTANT_Z, x = SM_POTENTIAL_CONSTANT_X;
	const uint8_t elastic = SM_POTENTIAL_ELASTIC;
	const struct {
		const char* name;
		uint8_t terms;
	} expected[] = {
	    {"a", weight | elastic},     {"b", weight | elastic}, {"c", weight | x},
	    {"d", weight | x | elastic}, {"e", weight | elastic}, {"r[0]", weight | elastic},
	    {"r[2]", weight | elastic},  {"s[0]", weight},        {"s[1]", weight},
	};
	const int32_t n = sm_document_particle_count(doc);
	ENSURE(n == 11);
	uint8_t terms[11];
	sm_document_potential_terms(doc, terms);
	for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++) {
		const int32_t i = sm_document_particle_index(doc, expected[e].name);
		ENSURE(i >= 0);
		if (terms[i] != expected[e].terms)
			printf("  particle %s: terms %u, expected %u\n", expected[e].name, (unsigned)terms[i],
			       (unsigned)expected[e].terms);
		ENSURE(terms[i] == expected[e].terms);
	}
	sm_document_potential_terms(NULL, terms);  // nothing to fill
	sm_document_destroy(doc);
	// Gravity (0, 0, 0), the numbers: no weight term; a load's potential along the axes of its
	// components, a parameter at 0 along y included, none along x, which no load has.
	const char* zero_gravity =
	    "{\"springmass\": 1, \"name\": \"t\", \"parameters\": {\"fy\": 0}, \"gravity\": [0, 0, 0],"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]}, {\"name\": \"b\", \"position\": [1, 0, 0]},"
	    "   {\"name\": \"c\", \"position\": [2, 0, 0]}],"
	    " \"loads\": [{\"particle\": \"a\", \"force\": [0, 0, 1.5]}, {\"particle\": \"b\", \"force\": [0, \"fy\", 0]}]}";
	doc = parse_valid(zero_gravity, &err);
	ENSURE(doc != NULL);
	ENSURE(sm_document_particle_count(doc) == 3);
	sm_document_potential_terms(doc, terms);
	const uint8_t loaded[] = {SM_POTENTIAL_CONSTANT_Z, SM_POTENTIAL_CONSTANT_Y, 0};
	for (int i = 0; i < 3; i++) {
		if (terms[i] != loaded[i])
			printf("  zero gravity, particle %d: terms %u, expected %u\n", i, (unsigned)terms[i],
			       (unsigned)loaded[i]);
		ENSURE(terms[i] == loaded[i]);
	}
	sm_document_destroy(doc);
	return 0;
}

// The forces each spring can exert for some values of the parameters, and whether mass damping
// can: a stiffness or damping that is a parameter (at 0 included) or a number other than 0, per
// strain too, not a number 0; mass damping likewise, absent meaning 0.
static int test_force_terms(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"t\", \"parameters\": {\"k\": 0, \"d\": 0, \"c\": 0, \"alpha\": 0},"
	    " \"mass_damping\": \"alpha\","
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]}, {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 40},"
	    "   {\"a\": \"a\", \"b\": \"b\", \"damping\": 0.3}, {\"a\": \"a\", \"b\": \"b\"},"
	    "   {\"a\": \"a\", \"b\": \"b\", \"stiffness\": \"k\", \"damping\": \"d\"},"
	    "   {\"a\": \"a\", \"b\": \"b\", \"stiffness\": 0, \"strain_damping\": \"c\"},"
	    "   {\"a\": \"a\", \"b\": \"b\", \"strain_stiffness\": 20, \"strain_damping\": 0}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const uint8_t elastic = SM_FORCE_ELASTIC, damping = SM_FORCE_DAMPING;
	const uint8_t expected[] = {elastic, damping, 0, elastic | damping, damping, elastic};
	ENSURE(sm_document_spring_count(doc) == 6);
	uint8_t terms[6];
	ENSURE(sm_document_force_terms(doc, terms));  // alpha, a parameter at 0
	for (int s = 0; s < 6; s++) {
		if (terms[s] != expected[s])
			printf("  spring %d: terms %u, expected %u\n", s, (unsigned)terms[s], (unsigned)expected[s]);
		ENSURE(terms[s] == expected[s]);
	}
	sm_document_destroy(doc);
	// Mass damping a number: other than 0, 0, or absent (0). terms may be NULL.
	const char* cases[] = {"\"mass_damping\": 0.1,", "\"mass_damping\": 0,", ""};
	const bool damped[] = {true, false, false};
	for (int k = 0; k < 3; k++) {
		char model[256];
		snprintf(model, sizeof model,
		         "{\"springmass\": 1, \"name\": \"t\", %s \"particles\": [{\"position\": [0, 0, 0]}]}",
		         cases[k]);
		doc = parse_valid(model, &err);
		ENSURE(doc != NULL);
		ENSURE(sm_document_force_terms(doc, NULL) == damped[k]);
		sm_document_destroy(doc);
	}
	ENSURE(!sm_document_force_terms(NULL, terms));
	return 0;
}

// The unit of what each parameter stands for, from the keys naming it: one unit per kind of key
// (a per-section constant in the unit its structure's section gives it: a sheet's width, a
// block's area); none for a count, an index, atol (positions and velocities), a single spring's
// per-section constant, two units at once, or nothing.
static int test_parameter_units(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"u\", \"parameters\": {\"m\": 1, \"x\": 0, \"v\": 0, \"k\": 5,"
	    " \"c\": 0.1, \"E\": 10, \"Ys\": 100, \"Yb\": 1000, \"Yd\": 1, \"Ds\": 0.5, \"rho\": 1, \"n\": 4,"
	    " \"g\": -9.81, \"alpha\": 0.1, \"brk\": 0.5, \"tol\": 1e-6, \"atol\": 1e-8, \"h\": 1e-3,"
	    " \"both\": 2, \"single\": 3, \"spare\": 3, \"l\": 0.5},"
	    " \"gravity\": [0, 0, \"g\"], \"mass_damping\": \"alpha\","
	    " \"particles\": [{\"name\": \"p\", \"position\": [\"x\", 0, 5], \"velocity\": [\"v\", 0, 0], \"mass\": \"m\"},"
	    "                 {\"name\": \"q\", \"position\": [1, 0, 5], \"mass\": \"both\"}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": \"q\", \"stiffness\": \"k\", \"damping\": \"c\","
	    "               \"break_strain\": \"brk\", \"rest_length\": \"l\"},"
	    "             {\"a\": \"p\", \"b\": \"q\", \"strain_stiffness\": \"E\", \"damping\": \"both\"},"
	    "             {\"a\": \"p\", \"b\": \"q\", \"section_stiffness\": \"single\", \"section\": 0.1}],"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"nu\": \"n\", \"nv\": 3,"
	    "   \"structural\": {\"section_stiffness\": \"Ys\", \"section_damping\": \"Ds\"}},"
	    "  {\"type\": \"block\", \"name\": \"b\", \"origin\": [5, 0, 0], \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2,"
	    "   \"nw\": 2, \"edge\": {\"section_stiffness\": \"Yb\", \"section_damping\": \"Yd\"}},"
	    "  {\"type\": \"mesh\", \"name\": \"t\", \"density\": \"rho\", \"vertices\": [[0, 0, 2], [1, 0, 2], [0, 1, 2]],"
	    "   \"triangles\": [[0, 1, 2]], \"edge\": {\"section_stiffness\": \"Ys\"}}],"
	    " \"fixed\": [\"s[0, n - 1]\"],"
	    " \"simulation\": {\"rtol\": \"tol\", \"atol\": \"atol\", \"max_step\": \"h\"}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const struct {
		const char* name;
		const char* unit;
	} expected[] = {
	    {"m", "kg"},   {"x", "m"},       {"v", "m/s"},     {"k", "N/m"},    {"c", "N.s/m"},   {"E", "N"},
	    {"Ys", "N/m"}, {"Yb", "N/m2"},   {"Yd", "N.s/m2"}, {"Ds", "N.s/m"}, {"rho", "kg/m2"}, {"n", ""},
	    {"g", "m/s2"}, {"alpha", "1/s"}, {"brk", "1"},     {"tol", "1"},    {"atol", ""},     {"h", "s"},
	    {"both", ""},  {"single", ""},   {"spare", ""},    {"l", "m"},
	};
	for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++) {
		const char* unit =
		    sm_document_parameter_unit(doc, sm_document_parameter_index(doc, expected[e].name));
		if (unit == NULL || strcmp(unit, expected[e].unit) != 0)
			printf("  parameter %s: unit \"%s\", expected \"%s\"\n", expected[e].name, unit ? unit : "(null)",
			       expected[e].unit);
		ENSURE(unit != NULL && strcmp(unit, expected[e].unit) == 0);
	}
	ENSURE(sm_document_parameter_unit(doc, -1) == NULL && sm_document_parameter_unit(doc, 99) == NULL);
	ENSURE(sm_document_parameter_unit(NULL, 0) == NULL);
	// The units stay when a value changes the counts.
	ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), 6.0, &err), SM_OK);
	ENSURE(strcmp(sm_document_parameter_unit(doc, sm_document_parameter_index(doc, "Ys")), "N/m") == 0);
	sm_document_destroy(doc);
	return 0;
}

// An initial state (e.g. a static equilibrium) replaces positions but keeps rest lengths, and
// survives saving and loading.
static int test_initial_state_and_save_to_file(void)
{
	sm_document* doc = load_bundled("hanging_rope", NULL);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	const int32_t n = sm_model_particle_count(m);
	double* x = malloc(3 * (size_t)n * sizeof(double));
	ENSURE(x != NULL);
	sm_model_initial_state(m, x, NULL);
	// Hang the rope straight down, each segment stretched by 10 %.
	for (int32_t i = 0; i < n; i++) {
		x[3 * i + 0] = 0.0;
		x[3 * i + 2] = -0.055 * i;
	}
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, NULL, NULL), SM_OK);
	const char* path = "test_model_file_saved.json";
	sm_error err = {SM_OK, ""};
	ENSURE_STATUS(sm_document_save(doc, path, &err), SM_OK);
	// A missing document is named as the caller's: the message is the save's, not that of the
	// function it writes the text with.
	ENSURE_STATUS(sm_document_save(NULL, path, &err), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(strcmp(err.message, "sm_document_save: no document") == 0);
	sm_document* again = sm_document_load(path, &err);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	// The file holds the canonical text to its last byte, the line end after the closing brace.
	char* canonical = sm_document_to_json(doc, &err);
	FILE* saved = fopen(path, "rb");
	ENSURE(canonical != NULL && saved != NULL);
	const size_t length = strlen(canonical);
	char* read_back = malloc(length + 2);
	const size_t got = read_back != NULL ? fread(read_back, 1, length + 2, saved) : 0;
	fclose(saved);
	const bool whole = got == length && memcmp(read_back, canonical, length) == 0;
	free(read_back);
	free(canonical);
	ENSURE(whole);
	// The parameters of the rope's total mass and its segment count fed only what the saved file
	// writes out as numbers (each particle's mass, the particles): they are left out; those of its
	// springs' constants and of the mass damping stay, feeding what they fed.
	ENSURE(sm_document_parameter_index(again, "mass") == -1 && sm_document_parameter_index(again, "n") == -1);
	ENSURE(sm_document_parameter_count(again) == 3);
	ENSURE(sm_document_parameter_uses(again, sm_document_parameter_index(again, "E")) ==
	       SM_PARAMETER_CONSTANTS);
	ENSURE(sm_document_parameter_uses(again, sm_document_parameter_index(again, "alpha")) ==
	       SM_PARAMETER_CONSTANTS);
	sm_model* m2 = NULL;
	ENSURE_STATUS(sm_document_build(again, &m2, NULL), SM_OK);
	sm_particle_def p;
	sm_model_get_particle(m2, 20, &p);
	ENSURE(p.position[2] == -0.055 * 20 && p.position[0] == 0.0);
	double l0;
	sm_model_spring_constants(m2, 0, &l0, NULL, NULL);
	ENSURE_NEAR(l0, 0.05, 1e-15);
	// A file that cannot be written is named with the reason.
	ENSURE_STATUS(sm_document_save(doc, "no_such_folder/x.json", &err), SM_ERROR_FILE);
	ENSURE(strcmp(err.message, "no_such_folder/x.json: cannot write: No such file or directory") == 0);
	if (access("/dev/full", W_OK) == 0) {
		ENSURE_STATUS(sm_document_save(doc, "/dev/full", &err), SM_ERROR_FILE);
		ENSURE(strcmp(err.message, "/dev/full: cannot write: No space left on device") == 0);
	}
	// A save that fails on the way (here a file size limit below the model's size, as a full disk
	// would) leaves the file it would replace as it was, and nothing beside it; one that succeeds
	// replaces it with its permissions.
	FILE* earlier = fopen(path, "w");
	ENSURE(earlier != NULL && fputs("earlier", earlier) >= 0 && fclose(earlier) == 0 &&
	       chmod(path, 0640) == 0);
	struct rlimit limit, small = {100, 100};
	ENSURE(getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur > 100);
	small.rlim_max = limit.rlim_max;
	void (*handler)(int) = signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
	ENSURE(setrlimit(RLIMIT_FSIZE, &small) == 0);
	const sm_status limited = sm_document_save(doc, path, &err);
	ENSURE(setrlimit(RLIMIT_FSIZE, &limit) == 0);
	signal(SIGXFSZ, handler);
	ENSURE_STATUS(limited, SM_ERROR_FILE);
	ENSURE(strcmp(err.message, "test_model_file_saved.json: cannot write: File too large") == 0);
	char kept[16] = "";
	earlier = fopen(path, "r");
	ENSURE(earlier != NULL && fgets(kept, sizeof kept, earlier) != NULL && fclose(earlier) == 0);
	ENSURE(strcmp(kept, "earlier") == 0);
	ENSURE_STATUS(sm_document_save(doc, path, &err), SM_OK);
	struct stat st;
	ENSURE(stat(path, &st) == 0 && (st.st_mode & 0777) == 0640 && st.st_size > 100);
	// This process's temporaries only (.springmass-<pid>-<n>.partial): another test may be saving
	// in the same folder at the same time.
	char own[64];
	snprintf(own, sizeof own, ".springmass-%ld-", (long)getpid());
	DIR* folder = opendir(".");
	ENSURE(folder != NULL);
	for (struct dirent* e = readdir(folder); e != NULL; e = readdir(folder))
		ENSURE(strncmp(e->d_name, own, strlen(own)) != 0);
	closedir(folder);
	// A name as long as a file system takes (255 bytes) is saved too: the temporary beside it is
	// short.
	char longest[256];
	memset(longest, 'm', 250);
	strcpy(longest + 250, ".json");
	ENSURE_STATUS(sm_document_save(doc, longest, &err), SM_OK);
	ENSURE(unlink(longest) == 0);
	// The elastic energy of the stretched rope: 20 springs of ks = E / l0 stretched by 10 % of
	// l0 store (E / l0) (0.1 l0)^2 / 2 = E l0 0.01 / 2 each (relative rounding ~1e-15; 1e-9
	// leaves room for the positions -0.055 i not being exact in binary).
	double* x2 = malloc(3 * (size_t)n * sizeof(double));
	ENSURE(x2 != NULL);
	sm_model_initial_state(m2, x2, NULL);
	const sm_energies e = sm_model_energies(m2, x2, NULL);
	ENSURE_REL(e.elastic, 20 * 2000.0 * 0.05 * 0.01 / 2.0, 1e-9, 0.0);
	free(x);
	free(x2);
	remove(path);
	sm_model_destroy(m);
	sm_model_destroy(m2);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// References: by name, by index, into a structure's grid with any spacing.
static int test_references(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"refs\", \"gravity\": [0, 0, 0],"
	    " \"particles\": [{\"name\": \"hook\", \"position\": [0, 0, 2], \"fixed\": true}],"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"nu\": 3, \"nv\": 2,"
	    "   \"structural\": {\"stiffness\": 5}},"
	    "  {\"type\": \"block\", \"name\": \"b\", \"origin\": [5, 0, 0], \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2,"
	    "   \"nw\": 2, \"edge\": {\"stiffness\": 1}}],"
	    " \"springs\": [{\"a\": \"hook\", \"b\": \"s[ 1 , 2 ]\", \"stiffness\": 7, \"rest_length\": 0},"
	    "  {\"a\": 0, \"b\": \"b[1,0,1]\", \"strain_stiffness\": 7},"
	    "  {\"a\": \"s[5]\", \"b\": \"b[0]\", \"damping\": 3}],"
	    " \"ports\": [{\"name\": \"p\", \"particle\": \"s[0,0]\", \"kind\": \"probe\"},"
	    "  {\"name\": \"q\", \"particle\": \"s[0,0]\", \"kind\": \"probe\"}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse(text, &err);
	if (doc == NULL) {
		printf("  %s\n", err.message);
		return 1;
	}
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	// hook 0, sheet 1..6 (row 1 column 2 is 1 + 1*3 + 2 = 6), block 7..14.
	ENSURE(sm_model_particle_count(m) == 1 + 6 + 8);
	const int32_t first = sm_model_spring_count(m) - 3;
	sm_spring_def s;
	sm_model_get_spring(m, first, &s);
	ENSURE(s.a == 0 && s.b == 6 && s.kind == SM_SPRING_ZERO_LENGTH);
	sm_model_get_spring(m, first + 1, &s);
	// b[1,0,1]: row 1, column 0, layer 1 of a 2 x 2 x 2 block: 7 + (1*2 + 1)*2 + 0 = 13.
	ENSURE(s.a == 0 && s.b == 13 && s.stiffness_scaling == SM_PER_STRAIN);
	ENSURE_NEAR(s.rest_length, sqrt(25.0 + 1.0 + 1.0), 1e-12);
	sm_model_get_spring(m, first + 2, &s);
	ENSURE(s.a == 6 && s.b == 7 && s.damping == 3.0 && s.stiffness == 0.0);
	ENSURE(strcmp(sm_document_particle_name(doc, 13), "b[1,0,1]") == 0);
	ENSURE(sm_document_port(doc, 1).particle == 1);
	ENSURE(sm_document_port_index(doc, "q") == 1);
	// The structures as their builders made them: the sheet's (nu-1) nv + nu (nv-1) = 7
	// structural springs come first, then the block's 3 * (1 * 2 * 2) = 12 edges.
	ENSURE(sm_document_structure_count(doc) == 2);
	const sm_structure_info sheet = sm_document_structure(doc, 0), block = sm_document_structure(doc, 1);
	ENSURE(strcmp(sheet.name, "s") == 0 && strcmp(sheet.type, "sheet") == 0);
	ENSURE(sheet.range.first_particle == 1 && sheet.range.particle_count == 6 && sheet.range.shape[0] == 3 &&
	       sheet.range.shape[1] == 2 && sheet.range.first_spring == 0 && sheet.range.spring_count == 7);
	ENSURE(sheet.range.group_spring_count[0] == 7 && sheet.range.group_spring_count[1] == 0 &&
	       sheet.range.group_spring_count[2] == 0);
	ENSURE(strcmp(block.name, "b") == 0 && strcmp(block.type, "block") == 0);
	ENSURE(block.range.first_particle == 7 && block.range.particle_count == 8 &&
	       block.range.first_spring == 7 && block.range.spring_count == 12 &&
	       block.range.group_spring_count[0] == 12);
	ENSURE(sm_structure_particle(&block.range, 1, 0, 1) == 13);
	ENSURE(sm_document_structure(doc, 2).name == NULL && sm_document_structure(doc, -1).name == NULL);
	ENSURE(sm_document_structure_count(NULL) == 0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A text that must be refused with exactly this status and message.
typedef struct refusal {
	const char* text;
	sm_status status;
	const char* message;
} refusal;

// Parses each text; prints those not refused as they must be, and returns how many.
static int count_wrong_refusals(const refusal* cases, size_t count)
{
	int failures = 0;
	for (size_t c = 0; c < count; c++) {
		sm_error err = {SM_OK, ""};
		sm_document* doc = parse(cases[c].text, &err);
		if (doc != NULL || err.status != cases[c].status || strcmp(err.message, cases[c].message) != 0) {
			printf("  case %zu: status %d, message\n    \"%s\"\n  expected %d,\n    \"%s\"\n", c,
			       (int)err.status, err.message, (int)cases[c].status, cases[c].message);
			sm_document_destroy(doc);
			failures++;
		}
	}
	return failures;
}

// "loads": constant forces on particles named or referred to in a structure, from numbers or
// parameters (in N, tunable), adding up on one particle; the model holds them as the particles'
// loads, and the canonical form writes them back as given. A load on no particle, a force that
// is not three finite numbers, and loads whose sum overflows are refused with their place.
static int test_loads(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"l\", \"parameters\": {\"F\": 2.5, \"n\": 3},"
	    " \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 5]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0],"
	    "   \"segments\": \"n\", \"structural\": {\"stiffness\": 10}}],"
	    " \"fixed\": [\"r[0]\"],"
	    " \"loads\": [{\"particle\": \"r[n]\", \"force\": [0, 0, \"F\"]}, {\"particle\": \"p\", \"force\": [1, 2, 3]},"
	    "             {\"particle\": \"r[n]\", \"force\": [0.5, 0, 1]}, {\"particle\": \"r[0]\", \"force\": [0, 7, 0]}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, &err), SM_OK);
	// Particle 0 is p, the rope's particles 1 to 4: r[3] is particle 4, r[0] particle 1 (held).
	const double expected[5][3] = {{1, 2, 3}, {0, 7, 0}, {0, 0, 0}, {0, 0, 0}, {0.5, 0, 3.5}};
	for (int32_t i = 0; i < 5; i++) {
		sm_particle_def def;
		ENSURE_STATUS(sm_model_get_particle(m, i, &def), SM_OK);
		ENSURE(def.load[0] == expected[i][0] && def.load[1] == expected[i][1] &&
		       def.load[2] == expected[i][2]);
	}
	const int32_t F = sm_document_parameter_index(doc, "F");
	ENSURE(sm_document_parameter_uses(doc, F) == SM_PARAMETER_CONSTANTS);
	ENSURE(strcmp(sm_document_parameter_unit(doc, F), "N") == 0);
	sm_model_destroy(m);
	// A new value of F moves the load with it.
	ENSURE_STATUS(sm_document_set_parameter(doc, F, -1.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, &err), SM_OK);
	sm_particle_def tip;
	ENSURE_STATUS(sm_model_get_particle(m, 4, &tip), SM_OK);
	ENSURE(tip.load[2] == 0.0);
	sm_model_destroy(m);
	// The canonical form keeps the loads as given, F by name.
	char* json = sm_document_to_json(doc, &err);
	ENSURE(json != NULL);
	ENSURE(strstr(json, "\"loads\": [\n    {\"particle\": \"r[3]\", \"force\": [0, 0, \"F\"]},") != NULL);
	sm_document* again = parse_valid(json, &err);
	free(json);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0]}],"
		 " \"loads\": [{\"particle\": \"q\", \"force\": [0, 0, 1]}]}",
		 SM_ERROR_NOT_FOUND, "test.json: loads[0].particle: no particle named \"q\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0]}],"
		 " \"loads\": [{\"particle\": \"p\", \"force\": [0, 1]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: loads[0].force: must be an array of 3 numbers [x, y, z], not an array of another length"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0]}],"
		 " \"loads\": [{\"particle\": \"p\"}]}",
		 SM_ERROR_SCHEMA, "test.json: loads[0]: missing required key \"force\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0]}],"
		 " \"loads\": [{\"particle\": \"p\", \"force\": [1, 0, 0], \"moment\": [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA, "test.json: loads[0]: unknown key \"moment\" (allowed here: particle, force)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"big\": 1e308}, \"particles\": [{\"name\": \"p\","
		 " \"position\": [0, 0, 0]}], \"loads\": [{\"particle\": \"p\", \"force\": [\"big\", 0, 0]},"
		 " {\"particle\": \"p\", \"force\": [\"big\", 0, 0]}]}",
		 SM_ERROR_NOT_FINITE,
		 "test.json: loads[1]: particle 0: load x = inf N is not finite (with parameter big = 1e+308)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [], \"loads\": {}}", SM_ERROR_SCHEMA,
		 "test.json: loads: must be an array of loads, not an object"},
	};
	ENSURE(count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) == 0);
	return 0;
}

// Broken files, each with the exact error: status and message.
static int test_broken_files(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\",\n \"particles\": [}", SM_ERROR_SYNTAX,
		 "test.json:2:16: unexpected token near '}'"},
	    {"{\"springmass\": 1, \"springmass\": 1}", SM_ERROR_SYNTAX,
		 "test.json:1:19: duplicate object key near '\"springmass\"'"},
	    {"[1, 2]", SM_ERROR_SCHEMA, "test.json: a model file is a JSON object, not an array"},
	    {"{\"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: missing \"springmass\": 1 (the format version; is this a springmass model file?)"},
	    {"{\"springmass\": 2, \"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: springmass: format version must be 1 (this build reads version 1)"},
	    {"{\"springmass\": \"1\", \"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: springmass: format version must be the integer 1, not a string (no quotes)"},
	    {"{\"springmass\": 1.0, \"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: springmass: format version must be the integer 1, not a real number"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"gravty\": [0, 0, 0]}", SM_ERROR_SCHEMA,
		 "test.json: unknown key \"gravty\" (allowed here: springmass, name, description, parameters, "
		 "parameter_units, gravity, mass_damping, particles, springs, structures, fixed, loads, ports, simulation, "
		 "fmu)"},
	    {"{\"springmass\": 1, \"name\": \"my model\"}", SM_ERROR_SCHEMA,
		 "test.json: name: name \"my model\" must be an identifier (letters, digits and '_', not starting with a "
		 "digit)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"two\\nlines\"}", SM_ERROR_SCHEMA,
		 "test.json: description: must be one line: it has a line break, U+000A, at character 4"},
	    {"{\"springmass\": 1, \"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: the model has no particles (give \"particles\" or \"structures\")"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0]}]}", SM_ERROR_SCHEMA,
		 "test.json: particles[0].position: must be an array of 3 numbers [x, y, z], not an array of another length"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mas\": 1}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0]: unknown key \"mas\" (allowed here: name, position, velocity, mass, fixed)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mass\": 0}]}",
		 SM_ERROR_NEGATIVE, "test.json: particles[0].mass: 0 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]},"
		 " {\"name\": \"b\", \"position\": [1, 0, 0]}], \"springs\": [{\"a\": \"a\", \"b\": \"a\"}, {\"a\": \"a\","
		 " \"b\": \"b\"}, {\"a\": \"a\", \"b\": \"b\"}, {\"a\": \"a\", \"b\": \"bobb\"}]}",
		 SM_ERROR_SELF_SPRING,
		 "test.json: springs[0]: connects particle 0 (\"a\") to itself (a and b are the same particle)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]},"
		 " {\"name\": \"b\", \"position\": [1, 0, 0]}], \"springs\": [{\"a\": \"a\", \"b\": \"b\"}, {\"a\": \"a\","
		 " \"b\": \"b\"}, {\"a\": \"a\", \"b\": \"b\"}, {\"a\": \"a\", \"b\": \"bobb\"}]}",
		 SM_ERROR_NOT_FOUND, "test.json: springs[3].b: no particle named \"bobb\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 2}]}",
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: springs[0].b: particle index 2 is out of range (the model has 2 particles)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"kk\"}]}",
		 SM_ERROR_NOT_FOUND, "test.json: springs[0].stiffness: no parameter named \"kk\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"-.5\"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"-.5\" (a number is written without quotes)"},
	    // Only text that reads as a number whole is said to be one; an expression is said to be
	    // none a value takes (docs/model-format.md, "Parameters"); other text is just no name.
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"2 * k\"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"2 * k\" (a value is a number or a parameter's name: only the indices of a structure reference take "
		 "expressions)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"-k\"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"-k\" (a value is a number or a parameter's name: only the indices of a structure reference take "
		 "expressions)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"(k)\"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"(k)\" (a value is a number or a parameter's name: only the indices of a structure reference take "
		 "expressions)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"1e-3\"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"1e-3\" (a number is written without quotes)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"2k\"}]}",
		 SM_ERROR_NOT_FOUND, "test.json: springs[0].stiffness: no parameter named \"2k\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"1,5\"}]}",
		 SM_ERROR_NOT_FOUND, "test.json: springs[0].stiffness: no parameter named \"1,5\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 5}, \"particles\": [{\"position\": [0, 0, 0]},"
		 " {\"position\": [1, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \" 1 \"}]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \" 1 \" (a number is written without quotes)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": 1, \"strain_stiffness\": 1}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: springs[0]: give one of \"stiffness\", \"strain_stiffness\" and \"section_stiffness\", not more"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"strain_stiffness\": 1, \"rest_length\": 0}]}",
		 SM_ERROR_ZERO_REST_LENGTH,
		 "test.json: springs[0]: per-strain stiffness needs a rest length > 0 (rest length is 0)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"break_strain\": -0.1}]}",
		 SM_ERROR_NEGATIVE, "test.json: springs[0].break_strain: -0.1 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"kind\": \"cubic\"}]}",
		 SM_ERROR_SCHEMA, "test.json: springs[0].kind: must be \"rest_length\" or \"zero_length\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 4,"
		 " \"nv\": 4}], \"fixed\": [\"c[4,0]\"]}",
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: fixed[0]: \"c[4,0]\" is outside structure c (rows 0 to 3, columns 0 to 3, or [0] to [15])"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 4,"
		 " \"nv\": 4}], \"fixed\": [{\"min\": [5, 5, 5], \"max\": [6, 6, 6]}]}",
		 SM_ERROR_SCHEMA, "test.json: fixed[0]: the box from (5, 5, 5) to (6, 6, 6) contains no particle"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 4,"
		 " \"nv\": 4}, {\"type\": \"rope\", \"name\": \"c\", \"start\": [0, 0, 0], \"end\": [1, 0, 0],"
		 " \"segments\": 2}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[1].name: structure name \"c\" is already used"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"c[0,0]\", \"position\": [0, 0, 0]}],"
		 " \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 4, \"nv\": 4}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"c[0,0]\" reads as a reference to a particle of structure \"c\": give "
		 "the particle another name"},
	    // Two particles named like references to c and one to d: c's name is indexed once, for the
	    // first of its particles, and the second leaves it so (a second insertion that stored its
	    // entry took the name over from c to d, and c loaded beside them).
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"c[0]\", \"position\": [0, 0, 0]},"
		 " {\"name\": \"c[1]\", \"position\": [1, 0, 0]}, {\"name\": \"d[0]\", \"position\": [2, 0, 0]}],"
		 " \"structures\": [{\"type\": \"rope\", \"name\": \"c\", \"start\": [0, 1, 0], \"end\": [1, 1, 0],"
		 " \"segments\": 1}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"c[0]\" reads as a reference to a particle of structure \"c\": give "
		 "the particle another name"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"cube\", \"name\": \"c\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].type: must be \"rope\", \"sheet\", \"block\" or \"mesh\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 4,"
		 " \"nv\": 4, \"bend\": {\"strain_stiffnes\": 1}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].bend: unknown key \"strain_stiffnes\" (allowed here: stiffness, strain_stiffness, "
		 "section_stiffness, damping, strain_damping, section_damping, break_strain)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 1e9,"
		 " \"nv\": 4}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0].nu: 1000000000 must be a whole number from 2 to 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 40000,"
		 " \"nv\": 40000}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: the model would have 1600000000 particles, more than the limit of 4194304"},
	    // The springs the groups present make, in closed form: a 2100 x 2100 sheet's structural
	    // springs 2 * 2099 * 2100; a 161^3 block's edges 3 * 160 * 161^2 (its particles are within
	    // the limit); a rope's bending springs, one fewer than its segments.
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 2100,"
		 " \"nv\": 2100, \"structural\": {\"stiffness\": 1}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: the model would have 4410000 particles and 8815800 springs, more than the limit of "
		 "4194304 of each"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"c\", \"size\": [1, 1, 1],"
		 " \"nu\": 161, \"nv\": 161, \"nw\": 161, \"edge\": {\"stiffness\": 1}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: the model would have 12442080 springs, more than the limit of 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"c\", \"size\": [1, 1, 1],"
		 " \"nu\": 100, \"nv\": 100, \"nw\": 419, \"face_diagonal\": {\"damping\": 1}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: the model would have 24766038 springs, more than the limit of 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"structures\": [{\"type\":"
		 " \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 4194304, \"bending\":"
		 " {\"stiffness\": 1}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: the model would have 4194306 particles, more than the limit of 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"c\", \"size\": [1, 1, 1],"
		 " \"nu\": 4000000, \"nv\": 4000000, \"nw\": 4000000}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: 4000000 x 4000000 x 4000000 particles exceed the limit of 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"c\", \"size\": [1, 1, 1],"
		 " \"nu\": -3, \"nv\": 4, \"nw\": 4}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0].nu: -3 must be a whole number from 2 to 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1, 3]]}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0].triangles[0][2]: 3 must be a whole number from 0 to 2"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1]]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].triangles[0]: must be an array of 3 vertex indices, not of 2"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 2, \"bending\": {\"break_strain\": 0.5}}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].bending: gives no stiffness and no damping, so it would make no springs (give "
		 "stiffness, strain_stiffness or section_stiffness, or a damping; or leave the group out)"},
	    // An explicit rest length does not spare a spring a length that overflows: it could not run.
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]},"
		 " {\"name\": \"b\", \"position\": [1e200, 0, 0]}], \"springs\": [{\"a\": \"a\", \"b\": \"b\","
		 " \"rest_length\": 1, \"stiffness\": 1}]}",
		 SM_ERROR_NOT_FINITE,
		 "test.json: springs[0]: the initial distance between particles 0 and 1, 1e+200 m, is too large (its square "
		 "overflows: "
		 "particles joined by springs must be less than 1.3e154 m apart)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], [2, 0, 0]], \"triangles\": [[0, 1, 2]]}]}",
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0]: mesh: triangle 0 (0, 1, 2) has zero area (to rounding: twice its area is at "
		 "most 1e-12 times the product of its two longest edges)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"big\": 1e308}, \"particles\": [{\"position\":"
		 " [0, 0, 0]}, {\"position\": [1e-10, 0, 0]}], \"springs\": [{\"a\": 0, \"b\": 1, \"strain_stiffness\":"
		 " \"big\"}]}",
		 SM_ERROR_NOT_FINITE,
		 "test.json: springs[0]: stiffness E / l0 = 1e+308 / 1e-10 is not finite (with parameter big = 1e+308)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 1e400}}", SM_ERROR_SYNTAX,
		 "test.json:1:52: real number overflow near '1e400'"},
	    {"\xef\xbb\xbf{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 1e400}}", SM_ERROR_SYNTAX,
		 "test.json:1:52: real number overflow near '1e400'"},
	    // An escape the parser refuses only once it has read the string whole is at its backslash,
	    // not at the closing quote, where the parser stands (the first such escape of the string).
	    {"{\"springmass\": 1, \"name\": \"x\\u0000y\"}", SM_ERROR_SYNTAX,
		 "test.json:1:29: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\\u0000\": 1}}", SM_ERROR_SYNTAX,
		 "test.json:1:49: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a\\\"\\\\\\u0000 and \\u0000 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:53: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\ud83d\\ude00 \\ud800 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:61: invalid Unicode '\\uD800'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\udc00\"}", SM_ERROR_SYNTAX,
		 "test.json:1:48: invalid Unicode '\\uDC00' near '\"\\udc00\"'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\ud800\\u0041\"}", SM_ERROR_SYNTAX,
		 "test.json:1:48: invalid Unicode '\\uD800\\u0041' near '\"\\ud800\\u0041\"'"},
	    // A backslash escaped is no escape of what follows it, an escaped quote does not open the
	    // string, upper-case hexadecimal digits and the last low surrogate are found as well.
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a\\\\u0000 and \\u0000\"}", SM_ERROR_SYNTAX,
		 "test.json:1:61: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a\\u0000 and \\\" then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:49: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a \\uD800 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:50: invalid Unicode '\\uD800'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a \\udfff then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:50: invalid Unicode '\\uDFFF'"},
	    // The last pair of surrogates is a character like any other: the escape at fault is after it.
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\udbff\\udfff\\u0000\"}", SM_ERROR_SYNTAX,
		 "test.json:1:60: strings in a model file may not contain \\u0000"},
	    // A valid escape just before the one at fault, a digit 9 in it, a low surrogate before
	    // another, and a high one before what is not a low one: a "u" that no backslash escapes, an
	    // escape other than \u, a \u escape beyond the low surrogates.
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\u0041\\u0000 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:54: strings in a model file may not contain \\u0000"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\uD9AB then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:48: invalid Unicode '\\uD9AB'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\uDC00\\uDC00 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:48: invalid Unicode '\\uDC00'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\uD800xuDC00 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:48: invalid Unicode '\\uD800'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\uD800\\nDC00 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:48: invalid Unicode '\\uD800'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"\\uD800\\uE000 then a long text\"}",
		 SM_ERROR_SYNTAX, "test.json:1:48: invalid Unicode '\\uD800\\uE000'"},
	    // Lines end at LF, CR LF or a lone CR, as editors show them (the parser counts LF only).
	    {"{\r\"springmass\": 1,\r\n\"name\": \"x\",\r\"parameters\" {}}", SM_ERROR_SYNTAX,
		 "test.json:4:14: ':' expected near '{'"},
	    // The text near a syntax error is shown with what a terminal would act on escaped.
	    {"{\"springmass\": 1, \"name\": \"x\", \x1b[31m}", SM_ERROR_SYNTAX,
		 "test.json:1:32: string or '}' expected near '\\u001b'"},
	    {"{\"springmass\": 1, \"name\": \"\xe2\x80\xae\\q\"}", SM_ERROR_SYNTAX,
		 "test.json:1:30: invalid escape near '\"\\u202e\\q'"},
	    {"", SM_ERROR_SYNTAX, "test.json: the model file is empty (a model file is one JSON object)"},
	    {" \r\n\t\n", SM_ERROR_SYNTAX,
		 "test.json: the model file is empty (a model file is one JSON object)"},
	    {"\xef\xbb\xbf\n", SM_ERROR_SYNTAX,
		 "test.json: the model file is empty (a model file is one JSON object)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": NaN}}", SM_ERROR_SYNTAX,
		 "test.json:1:52: invalid token near 'NaN'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 99999999999999999999}}",
		 SM_ERROR_SYNTAX, "test.json:1:52: too big integer near '99999999999999999999'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"2k\": 1}}", SM_ERROR_SCHEMA,
		 "test.json: parameters.2k: name \"2k\" must be an identifier (letters, digits and '_', not starting with a "
		 "digit)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 3}], \"fixed\": [\"r[1,]\"]}",
		 SM_ERROR_SCHEMA,
		 "test.json: fixed[0]: \"r[1,]\": a number, a parameter or '(' expected; a structure reference is name[i], "
		 "name[row, column] or name[row, column, layer]"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"fixed\": [0.5]}",
		 SM_ERROR_SCHEMA, "test.json: fixed[0]: a particle index must be a whole number, not 0.5"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"fixed\": [1e300]}",
		 SM_ERROR_PARTICLE_INDEX,
		 "test.json: fixed[0]: particle index 1e+300 is out of range (the model has 1 particle)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": \"m\"}}", SM_ERROR_SCHEMA,
		 "test.json: parameters.k: a parameter's value must be a number, not a string"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"fixed\": true}],"
		 " \"ports\": [{\"name\": \"p\", \"particle\": 0, \"kind\": \"force\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: ports[0]: a force port needs a free particle, and particle 0 is fixed (use a motion or probe port)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"ports\": [{\"name\": \"p\", \"particle\": 0, \"kind\": \"push\"}]}",
		 SM_ERROR_SCHEMA, "test.json: ports[0].kind: must be \"force\", \"motion\" or \"probe\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"ports\": [{\"name\": \"p\", \"particle\": 0, \"kind\": \"probe\"}, {\"name\": \"p\", \"particle\": 1,"
		 " \"kind\": \"probe\"}]}",
		 SM_ERROR_SCHEMA, "test.json: ports[1].name: port name \"p\" is already used by ports[0]"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"simulation\": {\"solver\": \"gauss\"}}",
		 SM_ERROR_SCHEMA,
		 "test.json: simulation.solver: must be one of \"auto\", \"dense\", \"klu\", \"pcg\", \"cholmod\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"simulation\": {\"input_changes\": true}}",
		 SM_ERROR_SCHEMA, "test.json: simulation.input_changes: must be one of \"restart\", \"keep\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"simulation\": {\"stability_limit_detection\": \"off\"}}",
		 SM_ERROR_SCHEMA,
		 "test.json: simulation.stability_limit_detection: must be true or false, not a string"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"simulation\": {\"rtol\": 0}}",
		 SM_ERROR_NEGATIVE, "test.json: simulation.rtol: 0 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"fmu\": {\"particle_variables\": 0}}",
		 SM_ERROR_SCHEMA, "test.json: fmu.particle_variables: must be true or false, not a number"},
	};
	return count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) > 0;
}

// A growing text for generated model files.
typedef struct text {
	char* data;
	size_t length, capacity;
} text;

static void append(text* t, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void append(text* t, const char* format, ...)
{
	for (;;) {
		va_list args;
		va_start(args, format);
		// An empty text has no buffer yet: NULL + 0 is undefined, so nothing is formatted into it.
		const int n =
		    t->data != NULL ? vsnprintf(t->data + t->length, t->capacity - t->length, format, args) : -1;
		va_end(args);
		if (n >= 0 && (size_t)n < t->capacity - t->length) {
			t->length += (size_t)n;
			return;
		}
		t->capacity = t->capacity > 0 ? 2 * t->capacity : 1 << 20;
		t->data = realloc(t->data, t->capacity);
		if (t->data == NULL)
			abort();
	}
}

// Each box of "fixed" tests every particle, so a file holds at most 256 of them: 256 load, and the
// 257th is refused by its path, before it is tested, so that a short file cannot make loading
// test a box per few bytes against a large structure's every particle.
static int test_fixed_boxes_are_limited(void)
{
	for (int boxes = 256; boxes <= 257; boxes++) {
		text t = {NULL, 0, 0};
		append(&t, "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": "
		           "\"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 1000}], \"fixed\": [");
		for (int k = 0; k < boxes; k++)
			append(&t, "%s{\"min\": [%.4f, -1, -1], \"max\": [%.4f, 1, 1]}", k > 0 ? ", " : "",
			       (k - 0.4) * 1e-3, (k + 0.4) * 1e-3);
		append(&t, "]}");
		sm_error err = {SM_OK, ""};
		sm_document* doc = parse(t.data, &err);
		free(t.data);
		if (boxes == 256) {
			ENSURE(doc != NULL);
			sm_model* m = NULL;
			ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
			ENSURE(count_fixed(m) == 256);  // the rope's first 256 particles, 1 mm apart, one per box
			sm_model_destroy(m);
			sm_document_destroy(doc);
		} else {
			ENSURE(doc == NULL);
			ENSURE_STATUS(err.status, SM_ERROR_SCHEMA);
			printf("  %s\n", err.message);
			ENSURE(strcmp(err.message, "test.json: fixed[256]: more than 256 boxes (each box tests every "
			                           "particle): name the particles by reference") == 0);
		}
	}
	return 0;
}

// Saving keeps what the file says, for every kind of value the writer treats apart: a
// rest-length spring of rest length 0 (which a file without "kind" reads as zero-length),
// per-strain stiffness beside absolute damping and the reverse, a literal break strain, parameters
// whose value is 0 (their references kept, so that changing them later still acts), the "fmu"
// settings and a description with a tab. And after sm_document_set_initial_state, a position the
// file took from a parameter is saved as the new number, not as the parameter again.
static sm_document* save_and_load(const sm_document* doc)
{
	sm_error err = {SM_OK, ""};
	char* text = sm_document_to_json(doc, &err);
	if (text == NULL)
		return NULL;
	sm_document* again = sm_document_parse(text, strlen(text), "saved.json", &err);
	if (again == NULL)
		printf("  saved: %s\n%s\n", err.message, text);
	free(text);
	return again;
}

static int test_canonical_form_keeps_what_the_file_says(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"kept\", \"description\": \"a\\tb\","
	    " \"parameters\": {\"k0\": 0, \"c0\": 0, \"y\": 0.25},"
	    " \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0], \"fixed\": true},"
	    "  {\"name\": \"q\", \"position\": [0, \"y\", 0]}, {\"name\": \"r\", \"position\": [1, 0, 0]}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": \"q\", \"kind\": \"rest_length\", \"rest_length\": 0, \"stiffness\": 3},"
	    "  {\"a\": \"p\", \"b\": \"r\", \"strain_stiffness\": 50, \"damping\": 0.5, \"break_strain\": 0.2},"
	    "  {\"a\": \"q\", \"b\": \"r\", \"stiffness\": 7, \"strain_damping\": 0.25},"
	    "  {\"a\": \"q\", \"b\": \"r\", \"stiffness\": \"k0\", \"damping\": \"c0\"}],"
	    " \"fmu\": {\"particle_variables\": false}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);  // kinds, constants, scalings, settings
	ENSURE(strcmp(sm_document_description(again), "a\tb") == 0);
	ENSURE(!sm_document_get_settings(again).particle_variables);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_spring_def s;
	sm_model_get_spring(m, 0, &s);
	ENSURE(s.kind == SM_SPRING_REST_LENGTH && s.rest_length == 0.0);
	sm_model_get_spring(m, 1, &s);
	ENSURE(s.stiffness_scaling == SM_PER_STRAIN && s.damping_scaling == SM_ABSOLUTE && s.break_strain == 0.2);
	sm_model_get_spring(m, 2, &s);
	ENSURE(s.stiffness_scaling == SM_ABSOLUTE && s.damping_scaling == SM_PER_STRAIN);
	sm_model_destroy(m);
	// The zero parameters still feed the last spring: set in both documents, they give the same
	// spring (k = 4 N/m, d = 0.1 N s/m).
	const double values[3] = {4.0, 0.1, 0.25};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameters(again, values, &err), SM_OK);
	ENSURE(sm_document_parameter_uses(again, 0) == SM_PARAMETER_CONSTANTS);
	ENSURE(same_document(doc, again) == 0);
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_model_get_spring(m, 3, &s);
	ENSURE(s.stiffness == 4.0 && s.damping == 0.1);
	sm_model_destroy(m);
	sm_document_destroy(again);
	// A new initial state: q moves from (0, 0.25, 0) to (0, 0.5, 0.1); the saved file starts
	// there, and its parameter y no longer moves q.
	const double x[9] = {0, 0, 0, 0, 0.5, 0.1, 1, 0, 0};
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, NULL, &err), SM_OK);
	again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_particle_def q;
	sm_model_get_particle(m, 1, &q);
	ENSURE(q.position[0] == 0.0 && q.position[1] == 0.5 && q.position[2] == 0.1);
	sm_model_destroy(m);
	ENSURE(sm_document_parameter_uses(again, 2) == 0);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// A structure's name has at most 175 bytes, so that the names its particles get (a block's
// name[row,column,layer] adds up to 25 bytes) stay within the 200 bytes of any name: a model
// whose structures have the longest names saves to a file that loads to the same model (the
// saved file names every particle), and a longer structure name is refused naming the structure.
static int test_longest_structure_names_round_trip(void)
{
	char rope[176], block[177], text[1024];
	memset(rope, 'r', 175);
	rope[175] = '\0';
	memset(block, 'b', 175);
	block[175] = '\0';
	const char* format =
	    "{\"springmass\": 1, \"name\": \"long\", \"structures\": [{\"type\": \"rope\", \"name\": \"%s\","
	    " \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 10, \"structural\": {\"stiffness\": 5}},"
	    " {\"type\": \"block\", \"name\": \"%s\", \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2, \"nw\": 11,"
	    " \"edge\": {\"stiffness\": 5}}], \"fixed\": [\"%s[0]\"]}";
	snprintf(text, sizeof text, format, rope, block, rope);
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const char* last = sm_document_particle_name(doc, 11 + 43);
	ENSURE(last != NULL && strlen(last) == 175 + 8 && strcmp(last + 175, "[1,1,10]") == 0);
	char* saved = sm_document_to_json(doc, &err);
	ENSURE(saved != NULL);
	sm_document* again = sm_document_parse(saved, strlen(saved), "saved.json", &err);
	free(saved);
	if (again == NULL)
		printf("  saved: %s\n", err.message);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(sm_document_particle_index(again, last) == 11 + 43);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	block[175] = 'b';
	block[176] = '\0';
	snprintf(text, sizeof text, format, rope, block, rope);
	ENSURE(parse(text, &err) == NULL && err.status == SM_ERROR_SCHEMA);
	char expected[400];
	snprintf(
	    expected, sizeof expected,
	    "test.json: structures[1].name: structure name \"%.80s\"... has 176 bytes; a structure's name may have at "
	    "most 175, so that its particles' names (name[row,column,layer]) fit in 200",
	    block);
	ENSURE(strcmp(err.message, expected) == 0);
	return 0;
}

// A structure is counted against the limit of 4 194 304 springs with the springs of the groups
// it has, not of every group: a 69^3 block without springs (328 509 particles) loads, as does
// one with edge springs only (3 * 68 * 69^2 = 971 244); with all 13 neighbours of a particle
// counted they would have been 4.27 million springs, over the limit.
static int test_structure_limit_counts_the_groups_present(void)
{
	const char* format =
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"b\","
	    " \"size\": [1, 1, 1], \"nu\": 69, \"nv\": 69, \"nw\": 69%s}]}";
	const char* groups[] = {"", ", \"edge\": {\"stiffness\": 1}"};
	const int32_t springs[] = {0, 971244};
	for (int k = 0; k < 2; k++) {
		char text[300];
		snprintf(text, sizeof text, format, groups[k]);
		sm_error err = {SM_OK, ""};
		sm_document* doc = parse_valid(text, &err);
		ENSURE(doc != NULL);
		const sm_structure_info block = sm_document_structure(doc, 0);
		ENSURE(block.range.particle_count == 69 * 69 * 69 && block.range.spring_count == springs[k]);
		ENSURE(block.range.group_spring_count[0] == springs[k]);
		sm_document_destroy(doc);
	}
	return 0;
}

// Loading takes time proportional to the size of the model: every name (parameter, structure,
// particle, port) is found in constant time, and the fixed particles are fixed together. The
// model has N = 100 000 ropes r<i> of one segment from (x<i>, zero, zero) to (x<i>, one, zero),
// parameters x<i> = i before zero and one, a reference "r<i>[ 0 ]" (spaced, so that the rope is
// found by its name) fixing the start of each, and a probe port q<i> on the end of each. It is no
// timing test, but it needs linear loading to finish: it loads in about a second (most of it
// parsing the JSON), while the loader that searched linearly took minutes. Measured on that
// loader, one comparison of names took 5.2 ns for parameters (105 s for 200 000 references to
// 200 000 parameters, 2e10 comparisons), and each of the other searches grew as fast: 200 000
// ports 354 s, 150 000 ropes with a fixed particle each over 400 s. Here the 5 N references to
// parameters make N^2 / 2 + 4 N^2 = 4.5e10 comparisons (230 s), the ports 88 s, the ropes and
// their fixed particles over 170 s, each more than a minute.
static int test_large_model_loads(void)
{
	enum { N = 100000 };
	text t = {NULL, 0, 0};
	append(&t, "{\"springmass\": 1, \"name\": \"large\", \"parameters\": {");
	for (int i = 0; i < N; i++)
		append(&t, "\"x%d\": %d, ", i, i);
	append(&t, "\"zero\": 0, \"one\": 1},\n\"structures\": [");
	for (int i = 0; i < N; i++)
		append(&t,
		       "%s{\"type\": \"rope\", \"name\": \"r%d\", \"start\": [\"x%d\", \"zero\", \"zero\"],"
		       " \"end\": [\"x%d\", \"one\", \"zero\"], \"segments\": 1}",
		       i > 0 ? ", " : "", i, i, i);
	append(&t, "],\n\"fixed\": [");
	for (int i = 0; i < N; i++)
		append(&t, "%s\"r%d[ 0 ]\"", i > 0 ? ", " : "", i);
	append(&t, "],\n\"ports\": [");
	for (int i = 0; i < N; i++)
		append(&t, "%s{\"name\": \"q%d\", \"particle\": \"r%d[1]\", \"kind\": \"probe\"}", i > 0 ? ", " : "",
		       i, i);
	append(&t, "]}");
	sm_error err = {SM_OK, ""};
	sm_document* doc = sm_document_parse(t.data, t.length, "large.json", &err);
	free(t.data);
	if (doc == NULL)
		printf("  %s\n", err.message);
	ENSURE(doc != NULL);
	ENSURE(sm_document_parameter_count(doc) == N + 2 && sm_document_structure_count(doc) == N);
	ENSURE(sm_document_port_count(doc) == N);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 2 * N && sm_model_spring_count(m) == 0 && count_fixed(m) == N);
	for (int i = 0; i < N; i += 997) {
		char name[32];
		snprintf(name, sizeof name, "x%d", i);
		ENSURE(sm_document_parameter_index(doc, name) == i);
		snprintf(name, sizeof name, "q%d", i);
		ENSURE(sm_document_port_index(doc, name) == i && sm_document_port(doc, i).particle == 2 * i + 1);
		snprintf(name, sizeof name, "r%d[1]", i);
		ENSURE(sm_document_particle_index(doc, name) == 2 * i + 1);
		sm_particle_def start, end;
		sm_model_get_particle(m, 2 * i, &start);
		sm_model_get_particle(m, 2 * i + 1, &end);
		ENSURE(start.motion == SM_PARTICLE_FIXED && start.position[0] == i && start.position[1] == 0.0);
		ENSURE(end.motion == SM_PARTICLE_FREE && end.position[0] == i && end.position[1] == 1.0);
	}
	ENSURE(sm_document_parameter_index(doc, "one") == N + 1 &&
	       sm_document_parameter_index(doc, "x100000") == -1);
	ENSURE(sm_document_port_index(doc, "q") == -1 && sm_document_particle_index(doc, "r0[2]") == -1);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A particle's own name is checked against every structure's (a particle "r7[0]" beside a
// structure r7 would read as a reference to it) by a lookup, not by a search of the particles for
// each structure. Here N = 40 000 particles named like references, "s<i>[0]" (to structures that
// do not exist), stand beside N ropes r<i> of one segment, and the last particle takes the name of
// a reference to the last rope, which is refused. It is no timing test, but it needs linear
// loading to finish: it loads in well under a second, while the search made N^2 = 1.6e9
// comparisons of names, two minutes for each of the two files.
static int test_many_particles_beside_many_structures_load(void)
{
	enum { N = 40000 };
	for (int clash = 0; clash < 2; clash++) {
		text t = {NULL, 0, 0};
		append(&t, "{\"springmass\": 1, \"name\": \"beside\", \"particles\": [");
		for (int i = 0; i < N; i++)
			append(&t, "%s{\"name\": \"%c%d[0]\", \"position\": [%d, 0, 0]}", i > 0 ? ", " : "",
			       clash && i == N - 1 ? 'r' : 's', i, i);
		append(&t, "],\n\"structures\": [");
		for (int i = 0; i < N; i++)
			append(&t,
			       "%s{\"type\": \"rope\", \"name\": \"r%d\", \"start\": [%d, 1, 0], \"end\": [%d, 2, 0],"
			       " \"segments\": 1}",
			       i > 0 ? ", " : "", i, i, i);
		append(&t, "]}");
		sm_error err = {SM_OK, ""};
		sm_document* doc = sm_document_parse(t.data, t.length, "beside.json", &err);
		free(t.data);
		if (!clash) {
			if (doc == NULL)
				printf("  %s\n", err.message);
			ENSURE(doc != NULL && sm_document_particle_count(doc) == 3 * N);
			ENSURE(sm_document_particle_index(doc, "s0[0]") == 0);
			ENSURE(sm_document_particle_index(doc, "r0[0]") == N);
		} else {
			char expected[SM_ERROR_MESSAGE_CAPACITY];
			snprintf(expected, sizeof expected,
			         "beside.json: particles[%d].name: name \"r%d[0]\" reads as a reference to a particle of"
			         " structure \"r%d\": give the particle another name",
			         N - 1, N - 1, N - 1);
			ENSURE(doc == NULL && err.status == SM_ERROR_SCHEMA && strcmp(err.message, expected) == 0);
		}
		sm_document_destroy(doc);
	}
	return 0;
}

// Names and keys from the file appear in messages quoted as a JSON string holds them: control
// characters, line separators and the invisible characters that reorder text escaped (\u001b),
// so that a message cannot drive the terminal it is shown on, and cut after 80 bytes at a
// character boundary with "..." after the quote, so that it stays valid UTF-8.
static int test_messages_quote_text(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"\\u001b[31mred\", \"position\": [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"\\u001b[31mred\" has a control character, U+001B, at character 1"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"gra\\u202evity\": [0, 0, 0]}", SM_ERROR_SCHEMA,
		 "test.json: unknown key \"gra\\u202evity\" (allowed here: springmass, name, description, parameters, "
		 "parameter_units, gravity, mass_damping, particles, springs, structures, fixed, loads, ports, simulation, "
		 "fmu)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\\u001b\": 1}}", SM_ERROR_SCHEMA,
		 "test.json: parameters.k\\u001b: name \"k\\u001b\" has a control character, U+001B, at character 2"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mass\": \"a\\\"b\\\\c\"}]}",
		 SM_ERROR_NOT_FOUND, "test.json: particles[0].mass: no parameter named \"a\\\"b\\\\c\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 3}], \"fixed\": [\"r[1,\\n]\"]}",
		 SM_ERROR_SCHEMA,
		 "test.json: fixed[0]: \"r[1,\\u000a]\": a number, a parameter or '(' expected; a structure reference is name[i], name[row, column] or name[row, "
		 "column, layer]"},
	};
	ENSURE(count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) == 0);
	// "€" is 3 bytes: 26 of them fit in 80 bytes, and the 27th is not cut.
	char text[512] =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"fixed\": [\"";
	char expected[256] = "test.json: fixed[0]: no particle named \"";
	for (int k = 0; k < 30; k++)
		strcat(text, "\xe2\x82\xac");
	for (int k = 0; k < 26; k++)
		strcat(expected, "\xe2\x82\xac");
	strcat(text, "\"]}");
	strcat(expected, "\"...");
	sm_error err = {SM_OK, ""};
	ENSURE(parse(text, &err) == NULL);
	if (strcmp(err.message, expected) != 0)
		printf("  \"%s\"\n  expected \"%s\"\n", err.message, expected);
	ENSURE(strcmp(err.message, expected) == 0);
	return 0;
}

// Names hold no control characters (C0, DEL and C1) and no line breaks, and a description is
// one line (no LF, VT, FF, CR, NEL, U+2028 or U+2029) without control characters but tabs; the
// message names the character and its position in characters. Other characters are welcome.
static int test_names_and_descriptions_refuse_controls_and_line_breaks(void)
{
	static const struct {
		const char* name;
		const char* description;
		const char* message;  // NULL: loads
	} cases[] = {
	    {"\\u009b31mred", "",
		 "particles[0].name: name \"\\u009b31mred\" has a control character, U+009B, at character 1"},
	    {"\xc3\xa9\\u007f", "",
		 "particles[0].name: name \"\xc3\xa9\\u007f\" has a control character, U+007F, at character 2"},
	    {"a\\u2028b", "", "particles[0].name: name \"a\\u2028b\" has a line break, U+2028, at character 2"},
	    {"a", "a\\u0085b", "description: must be one line: it has a line break, U+0085, at character 2"},
	    {"a", "\xe2\x82\xac\xe2\x82\xac\\u2029",
		 "description: must be one line: it has a line break, U+2029, at character 3"},
	    {"a", "x\\u000by", "description: must be one line: it has a line break, U+000B, at character 2"},
	    {"a", "bold \\u001b[1m",
		 "description: has a control character, U+001B, at character 6 (a tab is the only one "
		 "allowed)"},
	    {"caf\xc3\xa9 \xe2\x82\xac", "a\\tb \xe2\x80\x94 c", NULL},
	};
	int failures = 0;
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		char text[300], expected[300];
		snprintf(
		    text, sizeof text,
		    "{\"springmass\": 1, \"name\": \"x\", \"description\": \"%s\", \"particles\": [{\"name\": \"%s\","
		    " \"position\": [0, 0, 0]}]}",
		    cases[c].description, cases[c].name);
		snprintf(expected, sizeof expected, "test.json: %s",
		         cases[c].message != NULL ? cases[c].message : "");
		sm_error err = {SM_OK, ""};
		sm_document* doc = parse(text, &err);
		const bool right =
		    cases[c].message != NULL ? doc == NULL && strcmp(err.message, expected) == 0 : doc != NULL;
		if (!right) {
			printf("  case %zu: \"%s\"\n  expected \"%s\"\n", c, doc != NULL ? "(loaded)" : err.message,
			       expected);
			failures++;
		}
		sm_document_destroy(doc);
	}
	return failures > 0;
}

// A value from a parameter names the parameter: a rule on one value at the value's own path
// (a block's size[1], a sheet's edge_u), a rule on several (parallel edges, a rope's ends too far
// apart, a triangle of zero area, a stiffness E / l0 that overflows, an empty box) with the
// parameters the element's values came from, the first four of them; a triangle that repeats a
// vertex with the parameters of its own vertex indices only, none when they are numbers.
static int test_messages_name_parameters(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"s\": 0}, \"structures\": [{\"type\": \"block\","
		 " \"name\": \"j\", \"size\": [1, \"s\", 1], \"nu\": 2, \"nv\": 2, \"nw\": 2}]}",
		 SM_ERROR_NEGATIVE, "test.json: structures[0].size[1]: parameter s = 0 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"w\": 0}, \"structures\": [{\"type\": \"sheet\","
		 " \"name\": \"c\", \"edge_u\": [\"w\", 0, 0], \"nu\": 2, \"nv\": 2}]}",
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0].edge_u: (parameter w = 0, 0, 0) m is zero: the sheet spans no area and its particles would "
		 "coincide"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"h\": 0.5}, \"structures\": [{\"type\": \"sheet\","
		 " \"name\": \"c\", \"edge_v\": [\"h\", 0, 0], \"nu\": 2, \"nv\": 2}]}",
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0]: sheet: edge_u = (1, 0, 0) m and edge_v = (0.5, 0, 0) m are parallel (|edge_u x edge_v| <= "
		 "1e-12 |edge_u| |edge_v|): the sheet spans no area and its particles would coincide (with parameter h = 0.5)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"a\": 1, \"b\": 2, \"c\": 3, \"d\": 4, \"e\": 5},"
		 " \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"origin\": [\"a\", \"b\", \"c\"], \"edge_u\": [\"d\","
		 " 0, 0], \"edge_v\": [\"e\", 0, 0], \"nu\": 2, \"nv\": 2}]}",
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0]: sheet: edge_u = (4, 0, 0) m and edge_v = (5, 0, 0) m are parallel (|edge_u x edge_v| <= "
		 "1e-12 |edge_u| |edge_v|): the sheet spans no area and its particles would coincide (with parameter a = 1, "
		 "parameter b = 2, parameter c = 3, parameter d = 4 and others)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"far\": 1e308, \"near\": -1e308}, \"structures\":"
		 " [{\"type\": \"rope\", \"name\": \"r\", \"start\": [\"far\", 0, 0], \"end\": [\"near\", 0, 0], \"segments\": 2}]}",
		 SM_ERROR_NOT_FINITE,
		 "test.json: structures[0]: rope: start (1e+308, 0, 0) m and end (-1e+308, 0, 0) m are too far apart: end - "
		 "start is beyond the largest double (with "
		 "parameter far = 1e+308 and parameter near = -1e+308)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"x\": 2}, \"structures\": [{\"type\": \"mesh\","
		 " \"name\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [\"x\", 0, 0]], \"triangles\": [[0, 1, 2]]}]}",
		 SM_ERROR_INVALID_ARGUMENT,
		 "test.json: structures[0]: mesh: triangle 0 (0, 1, 2) has zero area (to rounding: twice its area is at "
		 "most 1e-12 times the product of its two longest edges) (with parameter x = 2)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"x\": 2}, \"structures\": [{\"type\": \"mesh\","
		 " \"name\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [\"x\", 1, 0]], \"triangles\": [[0, 1, 1]]}]}",
		 SM_ERROR_SELF_SPRING, "test.json: structures[0]: mesh: triangle 0 (0, 1, 1) repeats a vertex"},
	    // A triangle whose vertex index comes from a parameter repeats a vertex through it: named, as
	    // the other triangles' parameters and the vertices' positions are not.
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"x\": 2, \"k\": 1, \"j\": 2}, \"structures\":"
		 " [{\"type\": \"mesh\", \"name\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [\"x\", 1, 0]],"
		 " \"triangles\": [[0, 1, \"j\"], [0, \"k\", 1]]}]}",
		 SM_ERROR_SELF_SPRING,
		 "test.json: structures[0]: mesh: triangle 1 (0, 1, 1) repeats a vertex (with parameter k = 1)"},
	    // Its first and last vertices alike.
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 0, \"j\": 2}, \"structures\":"
		 " [{\"type\": \"mesh\", \"name\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],"
		 " \"triangles\": [[0, 1, \"j\"], [\"k\", 1, 0]]}]}",
		 SM_ERROR_SELF_SPRING,
		 "test.json: structures[0]: mesh: triangle 1 (0, 1, 0) repeats a vertex (with parameter k = 0)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"big\": 1e308}, \"structures\": [{\"type\": \"rope\","
		 " \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1e-10, 0, 0], \"segments\": 1, \"structural\":"
		 " {\"strain_stiffness\": \"big\"}}]}",
		 SM_ERROR_NOT_FINITE,
		 "test.json: structures[0]: rope: structural spring between particles 0 and 1: spring 0: stiffness E / l0 = 1e+308 / "
		 "1e-10 is not finite (with parameter big = 1e+308)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"a\": 5}, \"particles\": [{\"position\": [0, 0, 0]}],"
		 " \"fixed\": [{\"min\": [\"a\", 5, 5], \"max\": [6, 6, 6]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: fixed[0]: the box from (parameter a = 5, 5, 5) to (6, 6, 6) contains no particle"},
	};
	ENSURE(count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) == 0);

	// Changing the parameter gives the same message, which names it once.
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse("{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"h\": 1}, \"structures\": [{\"type\":"
		      " \"sheet\", \"name\": \"c\", \"edge_v\": [0, \"h\", 0], \"nu\": 2, \"nv\": 2}]}",
		      &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 0.0, &err), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0].edge_v: (0, parameter h = 0, 0) m is zero: the sheet spans no "
	              "area and its particles would coincide") == 0);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 1e-300, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, -1e308, &err), SM_OK);
	sm_document_destroy(doc);
	return 0;
}

// Parameters set together are checked together: a rope from xa = 0 to xb = 1 with per-strain
// springs (which need a rest length > 0) moves to xa = 1, xb = 3 in one call, where setting xa
// first would make the rope a point. A refusal names the parameters that changed and leaves the
// document unchanged.
static int test_parameters_set_together(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse("{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"xa\": 0, \"xb\": 1},"
		      " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [\"xa\", 0, 0],"
		      " \"end\": [\"xb\", 0, 0], \"segments\": 2, \"structural\": {\"strain_stiffness\": 10}}]}",
		      &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, 1.0, &err), SM_ERROR_ZERO_REST_LENGTH);
	const double moved[2] = {1.0, 3.0};
	ENSURE_STATUS(sm_document_set_parameters(doc, moved, &err), SM_OK);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	double x[9];
	sm_model_initial_state(model, x, NULL);
	ENSURE(x[0] == 1.0 && x[3] == 2.0 && x[6] == 3.0);  // the rope's three particles, evenly spaced
	sm_model_destroy(model);
	const double point[2] = {2.0, 2.0};
	ENSURE_STATUS(sm_document_set_parameters(doc, point, &err), SM_ERROR_ZERO_REST_LENGTH);
	ENSURE(strstr(err.message, "(with parameter xa = 2 and parameter xb = 2)") != NULL);
	ENSURE(sm_document_parameter_value(doc, 0) == 1.0 && sm_document_parameter_value(doc, 1) == 3.0);
	const double infinite[2] = {1.0, INFINITY};
	ENSURE_STATUS(sm_document_set_parameters(doc, infinite, &err), SM_ERROR_NOT_FINITE);
	ENSURE(strstr(err.message, "parameters.xb") != NULL);
	ENSURE_STATUS(sm_document_set_parameters(doc, NULL, &err), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_document_set_parameters(NULL, moved, &err), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(sm_document_parameter_value(doc, 0) == 1.0 && sm_document_parameter_value(doc, 1) == 3.0);
	sm_document_destroy(doc);
	// A message that names none of the parameters that changed gets them after it, the last after
	// "and": here the count of a rope's segments, with an initial state set for its 3 particles.
	doc = parse("{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"a\": 1, \"b\": 2, \"n\": 2},"
	            " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
	            " \"end\": [\"b\", 0, 0], \"segments\": \"n\", \"mass\": \"a\"}]}",
	            &err);
	ENSURE(doc != NULL);
	const double state[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
	ENSURE_STATUS(sm_document_set_initial_state(doc, state, NULL, &err), SM_OK);
	const double three[3] = {2.0, 3.0, 3.0};
	ENSURE_STATUS(sm_document_set_parameters(doc, three, &err), SM_ERROR_TOPOLOGY);
	ENSURE(strcmp(err.message, "test.json: the model now has 4 particles but its initial state was set for 3 "
	                           "(with parameter a = 2, parameter b = 3 and parameter n = 3)") == 0);
	sm_document_destroy(doc);
	return 0;
}

// A particle index written as a whole real number (3.0, as a count may be written) is that index.
static int test_whole_real_index(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse_valid("{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]},"
		            " {\"position\": [1, 0, 0]}], \"fixed\": [1.0]}",
		            &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_particle_def p0, p1;
	sm_model_get_particle(m, 0, &p0);
	sm_model_get_particle(m, 1, &p1);
	ENSURE(p0.motion == SM_PARTICLE_FREE && p1.motion == SM_PARTICLE_FIXED);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// Springs are numbered structures first, then the explicit springs (docs/model-format.md,
// "Springs"), the other way round from particles: the explicit spring below, written first in
// the file, is the last of the model, after the rope's two structural springs.
static int test_springs_are_numbered_structures_first(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"springs\": [{\"a\": \"hook\", \"b\": \"r[0]\", \"stiffness\": 7}],"
	    " \"particles\": [{\"name\": \"hook\", \"position\": [0, 0, 1]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [2, 0, 0],"
	    " \"segments\": 2, \"structural\": {\"stiffness\": 5}}]}",
	    &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, &err), SM_OK);
	ENSURE(sm_model_particle_count(m) == 4 && sm_model_spring_count(m) == 3);
	ENSURE(sm_document_particle_index(doc, "hook") == 0 && sm_document_particle_index(doc, "r[0]") == 1);
	sm_spring_def s;
	for (int32_t k = 0; k < 2; k++) {
		ENSURE_STATUS(sm_model_get_spring(m, k, &s), SM_OK);
		ENSURE(s.a == 1 + k && s.b == 2 + k && s.stiffness == 5.0);
	}
	ENSURE_STATUS(sm_model_get_spring(m, 2, &s), SM_OK);
	ENSURE(s.a == 0 && s.b == 1 && s.stiffness == 7.0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A UTF-8 byte-order mark before the document is ignored (RFC 8259, section 8.1), and line and
// column numbers stay those an editor shows; one anywhere else is an error, and one alone leaves
// an empty file. A directory given as
// the model file says so.
static int test_byte_order_mark_and_directories(void)
{
	sm_error err = {SM_OK, ""};
	const char text[] =
	    "\xef\xbb\xbf{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}]}";
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL && strcmp(sm_document_name(doc), "x") == 0);
	sm_document_destroy(doc);
	const char late[] = "{\"springmass\": 1,\n\xef\xbb\xbf\"name\": \"x\"}";
	ENSURE(parse(late, &err) == NULL && err.status == SM_ERROR_SYNTAX);
	ENSURE(strncmp(err.message, "test.json:2:1: ", 15) == 0);
	// The mark is no text: a file of the mark alone, as of the mark and white space, is empty.
	static const char* const marks_alone[] = {"\xef\xbb\xbf", "\xef\xbb\xbf\n"};
	for (size_t k = 0; k < sizeof marks_alone / sizeof marks_alone[0]; k++) {
		ENSURE(parse(marks_alone[k], &err) == NULL && err.status == SM_ERROR_SYNTAX);
		ENSURE(strcmp(err.message, "test.json: the model file is empty (a model file is one JSON object)") ==
		       0);
	}

	ENSURE(sm_document_load(SPRINGMASS_MODELS_DIR, &err) == NULL);
	char expected[600];
	snprintf(expected, sizeof expected, "%s: cannot read: Is a directory", SPRINGMASS_MODELS_DIR);
	ENSURE(err.status == SM_ERROR_FILE && strcmp(err.message, expected) == 0);
	return 0;
}

// Only regular files are read: a device (/dev/zero was read without end) and a FIFO without a
// writer (whose opening waited for ever) are refused at once, and a file in /proc, whose size
// is 0, is read to its end. A NUL byte in the text is named at its line and column (columns
// count characters): the JSON parser took it for the end of the text.
static int test_special_files_and_nul_bytes(void)
{
	sm_error err = {SM_OK, ""};
	ENSURE(sm_document_load("/dev/zero", &err) == NULL);
	ENSURE(err.status == SM_ERROR_FILE &&
	       strcmp(err.message, "/dev/zero: cannot read: not a regular file") == 0);
	const char* fifo = "test_model_file_fifo.json";
	remove(fifo);
	ENSURE(mkfifo(fifo, 0600) == 0);
	alarm(60);  // an open that blocks ends the test (SIGALRM) rather than hanging it
	sm_document* doc = sm_document_load(fifo, &err);
	alarm(0);
	remove(fifo);
	ENSURE(doc == NULL && err.status == SM_ERROR_FILE);
	ENSURE(strcmp(err.message, "test_model_file_fifo.json: cannot read: not a regular file") == 0);
	if (access("/proc/self/status", R_OK) == 0) {
		ENSURE(sm_document_load("/proc/self/status", &err) == NULL && err.status == SM_ERROR_SYNTAX);
		ENSURE(strncmp(err.message, "/proc/self/status:1:", 20) == 0);
	}

	static const char nul_first_line[] = "{\"springmass\": 1, \"name\": \"a\"\0, \"particles\": []}";
	ENSURE(sm_document_parse(nul_first_line, sizeof nul_first_line - 1, "test.json", &err) == NULL);
	ENSURE(err.status == SM_ERROR_SYNTAX &&
	       strcmp(err.message, "test.json:1:30: a NUL byte (a model file is UTF-8 text without NUL bytes)") ==
	           0);
	static const char nul_after_euro[] = "{\"springmass\": 1,\n \"name\": \"\xe2\x82\xac\"\0}";
	ENSURE(sm_document_parse(nul_after_euro, sizeof nul_after_euro - 1, "test.json", &err) == NULL);
	ENSURE(strcmp(err.message, "test.json:2:13: a NUL byte (a model file is UTF-8 text without NUL bytes)") ==
	       0);
	return 0;
}

// Hostile input fails cleanly: deep nesting, a file that is not there, binary junk, a file cut
// short at every length (each prefix of a valid file is refused or loads, never crashes).
static int test_hostile_input(void)
{
	sm_error err = {SM_OK, ""};
	const size_t depth = 100000;
	char* deep = malloc(2 * depth + 1);
	ENSURE(deep != NULL);
	memset(deep, '[', depth);
	memset(deep + depth, ']', depth);
	deep[2 * depth] = '\0';
	ENSURE(sm_document_parse(deep, 2 * depth, "deep.json", &err) == NULL);
	ENSURE(err.status == SM_ERROR_SYNTAX && strstr(err.message, "maximum parsing depth") != NULL);
	free(deep);

	ENSURE(sm_document_load("no/such/model.json", &err) == NULL);
	ENSURE(err.status == SM_ERROR_FILE &&
	       strcmp(err.message, "no/such/model.json: cannot open: No such file or directory") == 0);
	const char junk[] = {'{', 0, 1, 2, '"', (char)0xff, '}'};
	ENSURE(sm_document_parse(junk, sizeof junk, "junk", &err) == NULL && err.status == SM_ERROR_SYNTAX);
	ENSURE(sm_document_parse(NULL, 0, "none", &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);

	char path[512];
	snprintf(path, sizeof path, "%s/two_mass_chain.json", SPRINGMASS_MODELS_DIR);
	FILE* f = fopen(path, "rb");
	ENSURE(f != NULL);
	char text[8192];
	const size_t length = fread(text, 1, sizeof text, f);
	fclose(f);
	int loaded = 0;
	for (size_t n = 0; n <= length; n++) {
		sm_document* doc = sm_document_parse(text, n, "cut.json", &err);
		loaded += doc != NULL;
		sm_document_destroy(doc);
	}
	// Only the whole file (and the whole file without its final newline) is a document.
	ENSURE(loaded == 2);
	sm_document_destroy(NULL);
	return 0;
}

// Writes text to the file at path; 0 on success.
static int write_text_file(const char* path, const char* text)
{
	FILE* f = fopen(path, "w");
	ENSURE(f != NULL);
	ENSURE(fputs(text, f) >= 0);
	ENSURE(fclose(f) == 0);
	return 0;
}

// A model file in folders whose path is longer than a message (four folders of 100 'é', 806 bytes
// before the file's name): messages name it, and the OBJ file beside it, by the end of the path
// ("..." and the last whole characters of the path that fit in 140 bytes with it), so that they
// end with what is wrong. The path was written whole: the message was cut at its 511th byte, inside
// the path and inside a character, and said nothing of the error. A control character in a model
// file's path is shown escaped, as in an OBJ file's path, rather than written to a terminal.
static int test_long_and_control_character_paths_in_messages(void)
{
	char folder[1024] = "";
	char component[201];
	for (int k = 0; k < 100; k++)
		memcpy(component + 2 * k, "\xc3\xa9", 2);
	component[200] = '\0';
	for (int k = 0; k < 4; k++) {
		if (k > 0)
			strcat(folder, "/");
		strcat(folder, component);
		ENSURE(mkdir(folder, 0700) == 0 || errno == EEXIST);
	}
	char bad[1100], meshed[1100];
	snprintf(bad, sizeof bad, "%s/bad.json", folder);
	snprintf(meshed, sizeof meshed, "%s/meshed.json", folder);
	ENSURE(write_text_file(bad, "{\"springmass\": 1,\n \"name\": \"x\" \"y\"}\n") == 0);
	ENSURE(write_text_file(meshed,
	                       "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", "
	                       "\"name\": \"m\", \"file\": \"missing.obj\", \"density\": 1}]}\n") == 0);
	sm_error err = {SM_OK, ""};
	sm_document* doc = sm_document_load(bad, &err);
	// 137 bytes after "...": the name and 64 'é' (128 bytes) of its folder.
	char expected[SM_ERROR_MESSAGE_CAPACITY];
	snprintf(expected, sizeof expected, "...%s/bad.json:2:14: '}' expected near '\"y\"' (or a ',' before it)",
	         component + 200 - 128);
	const bool syntax_shown =
	    doc == NULL && err.status == SM_ERROR_SYNTAX && strcmp(err.message, expected) == 0;
	if (!syntax_shown)
		printf("  %s\n", err.message);
	sm_document_destroy(doc);
	doc = sm_document_load(meshed, &err);
	// Names of 12 bytes: 62 'é' (124 bytes) of the folder fit before them, not 62.5.
	snprintf(
	    expected, sizeof expected,
	    "...%s/meshed.json: structures[0].file: ...%s/missing.obj: cannot open: No such file or directory",
	    component + 200 - 124, component + 200 - 124);
	const bool mesh_shown = doc == NULL && err.status == SM_ERROR_FILE && strcmp(err.message, expected) == 0;
	if (!mesh_shown)
		printf("  %s\n", err.message);
	sm_document_destroy(doc);
	remove(bad);
	remove(meshed);
	for (int k = 3; k >= 0; k--) {
		rmdir(folder);
		char* slash = strrchr(folder, '/');
		if (slash != NULL)
			*slash = '\0';
	}
	ENSURE(syntax_shown && mesh_shown);
	ENSURE(sm_document_load("no/such/\x1b[31mred.json", &err) == NULL);
	ENSURE(err.status == SM_ERROR_FILE &&
	       strcmp(err.message, "no/such/\\u001b[31mred.json: cannot open: No such file or directory") == 0);
	// The 140 bytes are those shown: a name of exactly 140 is shown whole, and one that passes them
	// only once its control characters (\u0001, 6 bytes each) or stray bytes (\xff, 4) are escaped
	// loses its start, keeping its end whole.
	static const char broken[] = "{\"springmass\": 1, \"name\": \"x\" \"y\"}";
	static const struct {
		const char* escaped;  // after 120 'a'
		const char* raw;
		int kept;  // of the 'a', after "..." (0: the name shown whole)
	} names[] = {
	    {"aaaaaaaaaaa/bad.json", "aaaaaaaaaaa/bad.json", 0},
	    {"\\u0001\\u0001\\u0001\\u0001/b.json", "\x01\x01\x01\x01/b.json", 106},
	    {"\\xff\\xff\\xff\\xff/b.json", "\xff\xff\xff\xff/b.json", 114},
	};
	for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
		char name[200], shown[400];
		memset(name, 'a', 120);
		strcpy(name + 120, names[k].raw);
		if (names[k].kept == 0)
			snprintf(shown, sizeof shown, "%s:1:", name);
		else
			snprintf(shown, sizeof shown, "...%.*s%s:1:", names[k].kept, name, names[k].escaped);
		ENSURE(names[k].kept > 0 || strlen(name) == 140);
		doc = sm_document_parse(broken, strlen(broken), name, &err);
		const bool cut_shown = doc == NULL && strncmp(err.message, shown, strlen(shown)) == 0;
		if (!cut_shown)
			printf("  %s\n", err.message);
		ENSURE(cut_shown);
	}
	return 0;
}

// Two free particles 1 m apart, the start of the files below.
#define TWO_PARTICLES                                                                                        \
	"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}]"

// The rules of docs/model-format.md at their edges, each refused with the path of the element,
// the value and the rule: a relative tolerance of 1 (it must be < 1) and one just under the machine
// epsilon, times of 0 and below, an
// absolute tolerance just under 1e-150, no internal steps (a simulation refuses max_steps 0, see
// test_settings_and_their_defaults), a negative largest step, a negative mass damping, a mesh of density 0, a
// spring's rest length of -1 (a rest length is >= 0, whatever the library uses -1 for), a zero-length spring
// with another rest length, a constant and a mass given both ways, required keys left out, a vector of four
// numbers, structure and port names that are not identifiers, and a port of another kind beside a probe on
// the same particle (only probes share a particle).
static int test_rules_at_their_edges(void)
{
	static const refusal cases[] = {
	    {TWO_PARTICLES ", \"simulation\": {\"rtol\": 1}}", SM_ERROR_SCHEMA,
		 "test.json: simulation.rtol: 1 must be < 1"},
	    {TWO_PARTICLES ", \"simulation\": {\"rtol\": 2e-16}}", SM_ERROR_SCHEMA,
		 "test.json: simulation.rtol: 2e-16 must be at least 2.220446049250313e-16, the machine epsilon (CVODE cannot meet a "
		 "smaller relative tolerance)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"tol\": 1e-17},"
		 " \"particles\": [{\"position\": [0, 0, 0]}], \"simulation\": {\"rtol\": \"tol\"}}",
		 SM_ERROR_SCHEMA,
		 "test.json: simulation.rtol: parameter tol = 1e-17 must be at least 2.220446049250313e-16, the machine epsilon (CVODE "
		 "cannot meet a smaller relative tolerance)"},
	    {TWO_PARTICLES ", \"simulation\": {\"output_interval\": 0}}", SM_ERROR_NEGATIVE,
		 "test.json: simulation.output_interval: 0 must be > 0"},
	    {TWO_PARTICLES ", \"simulation\": {\"stop_time\": -1}}", SM_ERROR_NEGATIVE,
		 "test.json: simulation.stop_time: -1 must be > 0"},
	    {TWO_PARTICLES ", \"simulation\": {\"atol_velocity\": 1e-151}}", SM_ERROR_SCHEMA,
		 "test.json: simulation.atol_velocity: 1e-151 must be at least 1e-150 (CVODE's error norm overflows below)"},
	    {TWO_PARTICLES ", \"simulation\": {\"max_steps\": 0}}", SM_ERROR_SCHEMA,
		 "test.json: simulation.max_steps: 0 must be a whole number from 1 to 2147483647"},
	    {TWO_PARTICLES ", \"simulation\": {\"max_step\": -0.001}}", SM_ERROR_NEGATIVE,
		 "test.json: simulation.max_step: -0.001 must be >= 0"},
	    {TWO_PARTICLES ", \"mass_damping\": -0.5}", SM_ERROR_NEGATIVE,
		 "test.json: mass_damping: -0.5 must be >= 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\", \"density\": 0,"
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2]]}]}",
		 SM_ERROR_NEGATIVE, "test.json: structures[0].density: 0 must be > 0"},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": 1, \"rest_length\": -1}]}",
		 SM_ERROR_NEGATIVE, "test.json: springs[0].rest_length: -1 must be >= 0"},
	    {TWO_PARTICLES
		 ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": 1, \"kind\": \"zero_length\", \"rest_length\": 0.5}]}",
		 SM_ERROR_SCHEMA, "test.json: springs[0]: a zero-length spring cannot have rest_length 0.5"},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"damping\": 1, \"strain_damping\": 1}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: springs[0]: give one of \"damping\", \"strain_damping\" and \"section_damping\", not more"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 2, \"mass\": 1, \"mass_per_length\": 1}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: give \"mass\" [kg] or \"mass_per_length\" [kg/m], not both"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"b\", \"nu\": 2, \"nv\": 2,"
		 " \"nw\": 2}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0]: missing required key \"size\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"end\": [1, 0, 0],"
		 " \"segments\": 2}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0]: missing required key \"start\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"segments\": 2}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0]: missing required key \"end\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\"}]}", SM_ERROR_SCHEMA,
		 "test.json: particles[0]: missing required key \"position\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0, 0]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].position: must be an array of 3 numbers [x, y, z], not an array of another length"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"my rope\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 2}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].name: name \"my rope\" must be an identifier (letters, digits and '_', not starting with "
		 "a digit)"},
	    {TWO_PARTICLES ", \"ports\": [{\"name\": \"tip 1\", \"particle\": 1, \"kind\": \"probe\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: ports[0].name: name \"tip 1\" must be an identifier (letters, digits and '_', not starting with a "
		 "digit)"},
	    {TWO_PARTICLES
		 ", \"ports\": [{\"name\": \"f\", \"particle\": 1, \"kind\": \"force\"}, {\"name\": \"p\", \"particle\": 1,"
		 " \"kind\": \"probe\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: ports[1]: particle 1 already has port f; only probe ports may share a particle"},
	    {TWO_PARTICLES
		 ", \"ports\": [{\"name\": \"p\", \"particle\": 1, \"kind\": \"probe\"}, {\"name\": \"m\", \"particle\": 1,"
		 " \"kind\": \"motion\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: ports[1]: particle 1 already has port p; only probe ports may share a particle"},
	    // A named particle is named too.
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 2}], \"fixed\": [\"r[0]\"],"
		 " \"ports\": [{\"name\": \"f\", \"particle\": \"r[0]\", \"kind\": \"force\"}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: ports[0]: a force port needs a free particle, and particle 0 (\"r[0]\") is fixed (use a motion or "
		 "probe port)"},
	};
	return count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) > 0;
}

// Whether text is refused with status and message; prints what happened otherwise, under `label`.
static bool refused_as(const char* text, const char* label, sm_status status, const char* message)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse(text, &err);
	const bool refused = doc == NULL && err.status == status && strcmp(err.message, message) == 0;
	if (!refused)
		printf("  %s: status %d, \"%s\"\n  expected %d, \"%s\"\n", label, (int)err.status,
		       doc != NULL ? "(loaded)" : err.message, (int)status, message);
	sm_document_destroy(doc);
	return refused;
}

// A reference outside its structure is refused, never taken for a particle beside it: particle
// p comes before rope r (4 particles), sheet c (4 x 4), block b (2 x 2 x 2) and rope s (2), so
// that one before r's first particle, or one past the end of a row, a layer or a structure, is a
// particle of the model. A block takes one or three coordinates, not two, a sheet one or two, a
// rope one (docs: "Referring to particles"), and an index is below the particle count (31), whether an
// integer or a whole real. Each reference is a spring's end, and the last part holds the last particles by
// "fixed".
static int test_references_stay_inside_their_structures(void)
{
	static const char* const format =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [9, 9, 9]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 3},"
	    "  {\"type\": \"sheet\", \"name\": \"c\", \"origin\": [0, 1, 0], \"nu\": 4, \"nv\": 4},"
	    "  {\"type\": \"block\", \"name\": \"b\", \"origin\": [0, 3, 0], \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2, \"nw\": 2},"
	    "  {\"type\": \"rope\", \"name\": \"s\", \"start\": [0, 5, 0], \"end\": [1, 5, 0], \"segments\": 1}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": %s, \"stiffness\": 1}], \"fixed\": [%s]}";
	static const struct {
		const char* reference;
		sm_status status;
		const char* message;
	} cases[] = {
	    {"\"r[4]\"", SM_ERROR_PARTICLE_INDEX, "\"r[4]\" is outside structure r ([0] to [3])"},
	    {"\"r[-1]\"", SM_ERROR_PARTICLE_INDEX, "\"r[-1]\" is outside structure r ([0] to [3])"},
	    {"\"c[0,4]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"c[0,4]\" is outside structure c (rows 0 to 3, columns 0 to 3, or [0] to [15])"},
	    {"\"b[0,1]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"b[0,1]\" has 2 indices: a block takes name[i] or name[row, column, layer]"},
	    {"\"r[0, 2]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"r[0, 2]\" has 2 indices: a rope takes one index, name[i]"},
	    {"\"r[0, 2, 0]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"r[0, 2, 0]\" has 3 indices: a rope takes one index, name[i]"},
	    {"\"c[1, 2, 0]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"c[1, 2, 0]\" has 3 indices: a sheet takes name[i] or name[row, column]"},
	    {"\"b[0,0,2]\"", SM_ERROR_PARTICLE_INDEX,
		 "\"b[0,0,2]\" is outside structure b (rows 0 to 1, columns 0 to 1, layers 0 to 1, or [0] to [7])"},
	    {"\"r[1]]\"", SM_ERROR_SCHEMA,
		 "\"r[1]]\": a structure reference is name[i], name[row, column] or name[row, column, layer]"},
	    // A syntax error in the third index is explained as in the first.
	    {"\"b[0, 0, )]\"", SM_ERROR_SCHEMA,
		 "\"b[0, 0, )]\": a number, a parameter or '(' expected; a structure reference is name[i], "
		 "name[row, column] or name[row, column, layer]"},
	    {"31", SM_ERROR_PARTICLE_INDEX, "particle index 31 is out of range (the model has 31 particles)"},
	    {"31.0", SM_ERROR_PARTICLE_INDEX, "particle index 31 is out of range (the model has 31 particles)"},
	    {"-1", SM_ERROR_PARTICLE_INDEX, "particle index -1 is out of range (the model has 31 particles)"},
	};
	int failures = 0;
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		char text[1024], expected[300];
		snprintf(text, sizeof text, format, cases[c].reference, "");
		snprintf(expected, sizeof expected, "test.json: springs[0].b: %s", cases[c].message);
		failures += !refused_as(text, cases[c].reference, cases[c].status, expected);
	}
	ENSURE(failures == 0);
	// The last particle of each structure, and of the model, by each form of reference: r 1..4,
	// c 5..20, b 21..28, s 29..30.
	char text[1024];
	snprintf(text, sizeof text, format, "30", "\"r[3]\", \"c[3,3]\", \"b[1,1,1]\", \"b[7]\", 30.0, 29");
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_particle_count(m) == 31 && count_fixed(m) == 5 && sm_model_spring_count(m) == 1);
	static const int32_t held[] = {4, 20, 28, 29, 30};
	for (size_t k = 0; k < sizeof held / sizeof held[0]; k++)
		ENSURE(sm_model_free_index(m, held[k]) == -1);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	// The ranges a message gives are the structure's own, rows along edge_v and columns along
	// edge_u, on grids longer one way than another: a sheet of 3 columns and 2 rows, a block of 2
	// columns, 3 rows and 4 layers.
	ENSURE(refused_as(
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\","
	    " \"nu\": 3, \"nv\": 2}], \"fixed\": [\"c[2,0]\"]}",
	    "sheet", SM_ERROR_PARTICLE_INDEX,
	    "test.json: fixed[0]: \"c[2,0]\" is outside structure c (rows 0 to 1, columns 0 to 2, or [0] "
	    "to [5])"));
	ENSURE(refused_as(
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"b\","
	    " \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 3, \"nw\": 4}], \"fixed\": [\"b[0,2,0]\"]}",
	    "block", SM_ERROR_PARTICLE_INDEX,
	    "test.json: fixed[0]: \"b[0,2,0]\" is outside structure b (rows 0 to 2, columns 0 to 1, "
	    "layers 0 to 3, or [0] to [23])"));
	// Index 0 written as a real is the first particle, as 3.0 is index 3.
	doc = parse_valid(TWO_PARTICLES ", \"springs\": [{\"a\": 0.0, \"b\": 1, \"stiffness\": 1}]}", &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_spring_def spring;
	sm_model_get_spring(m, 0, &spring);
	ENSURE(spring.a == 0 && spring.b == 1);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A mesh's particles are named by one index, its vertex's (docs: "Referring to particles"): two or
// three indices are refused with the forms it takes, as for a rope, and m[3] is its last vertex.
static int test_mesh_references_take_one_index(void)
{
	static const char* const format =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"p\", \"position\": [9, 9, 9]}],"
	    " \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
	    "  \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1]], \"triangles\": [[0, 1, 3], [0, 3, 2]]}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": %s, \"stiffness\": 1}]}";
	static const struct {
		const char* reference;
		const char* message;
	} cases[] = {
	    {"\"m[0, 2]\"", "\"m[0, 2]\" has 2 indices: a mesh takes one index, name[i]"},
	    {"\"m[0, 0, 0]\"", "\"m[0, 0, 0]\" has 3 indices: a mesh takes one index, name[i]"},
	    {"\"m[4]\"", "\"m[4]\" is outside structure m ([0] to [3])"},
	};
	int failures = 0;
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		char text[1024], expected[300];
		snprintf(text, sizeof text, format, cases[c].reference);
		snprintf(expected, sizeof expected, "test.json: springs[0].b: %s", cases[c].message);
		failures += !refused_as(text, cases[c].reference, SM_ERROR_PARTICLE_INDEX, expected);
	}
	ENSURE(failures == 0);
	char text[1024];
	snprintf(text, sizeof text, format, "\"m[3]\"");
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_spring_def s;
	ENSURE_STATUS(sm_model_get_spring(m, 0, &s), SM_OK);
	ENSURE(s.a == 0 && s.b == 4 && strcmp(sm_document_particle_name(doc, 4), "m[3]") == 0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// Dropping an initial state gives back the file's velocities too, not zeros: a particle that the
// file starts at 0.5 m/s (one from a parameter, w = -2) is at rest in a state set without
// velocities, and moves as the file says again once that state is dropped (the same numbers:
// compared exactly).
static int test_dropping_the_initial_state_restores_the_file_velocities(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse_valid("{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"w\": -2},"
		            " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true},"
		            " {\"name\": \"b\", \"position\": [0, 0, -1], \"velocity\": [0.5, 0, \"w\"]}],"
		            " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 10}]}",
		            &err);
	ENSURE(doc != NULL);
	const double lowered[6] = {0, 0, 0, 0, 0, -1.5};
	ENSURE_STATUS(sm_document_set_initial_state(doc, lowered, NULL, &err), SM_OK);
	sm_model* m = NULL;
	double x[6], v[6];
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_model_initial_state(m, x, v);
	ENSURE(x[5] == -1.5 && v[3] == 0.0 && v[5] == 0.0);
	sm_model_destroy(m);
	ENSURE_STATUS(sm_document_set_initial_state(doc, NULL, NULL, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_model_initial_state(m, x, v);
	ENSURE(x[5] == -1.0 && v[3] == 0.5 && v[4] == 0.0 && v[5] == -2.0);
	sm_model_destroy(m);
	char* saved = sm_document_to_json(doc, &err);
	ENSURE(saved != NULL && strstr(saved, "\"velocity\": [0.5, 0, \"w\"]") != NULL);
	free(saved);
	sm_document_destroy(doc);
	return 0;
}

// An index of a structure reference may be an expression of parameters (docs: "Referring to
// particles"): each case is worked out by hand as the position along a rope of 101 particles r
// (particles 1..101, after particle p), the end b of a spring from r[z] = r[0], with a = 7,
// b = -3, z = 0, h = 0.5 and big = 2^31. Division rounds down, also for negative quotients
// (-7 / 2 is -4, not C's -3). A message on the reference names its own parameters, not z of the
// spring's other end.
static int test_reference_expressions(void)
{
	static const char* const format =
	    "{\"springmass\": 1, \"name\": \"x\","
	    " \"parameters\": {\"a\": 7, \"b\": -3, \"z\": 0, \"h\": 0.5, \"big\": 2147483648, \"k\": 2,"
	    "   \"huge\": 2147483649, \"n_1\": 4, \"n2\": 5, \"_m\": 2},"
	    " \"particles\": [{\"name\": \"p\", \"position\": [9, 9, 9]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 100}],"
	    " \"springs\": [{\"a\": \"r[z]\", \"b\": \"%s\", \"stiffness\": \"k\"}]}";
	static const struct {
		const char* reference;
		int32_t position;
	} values[] = {
	    // The limits: 2^31 itself is allowed, as a literal and as -2^31 halved.
	    {"r[2147483648 - 2147483600]", 48},
	    {"r[(-2147483647 - 1) / 2 + 1073741834]", 10},
	    {"r[-8/2+10]", 6},
	    {"r[n_1]", 4},
	    {"r[n2]", 5},
	    {"r[\\n1\\r]", 1},
	    {"r[_m + 1]", 3},  // a parameter's name may begin with '_', as a C identifier may
	    {"r[--------------------------------1]", 1},  // 32 unary signs deep
	    {"r[a*2+1]", 15},
	    {"r[(a+1)*2]", 16},
	    {"r[a - 2 - 1]", 4},
	    {"r[a/2]", 3},
	    {"r[-b]", 3},
	    {"r[b/2+5]", 3},
	    {"r[7/-2+10]", 6},
	    {"r[-7/2+10]", 6},
	    {"r[100/a*a]", 98},
	    {"r[+a]", 7},
	    {"r[ a\\t* 2 ]", 14},
	    {"r[--a]", 7},
	    {"r[big - 2147483600]", 48},
	    {"r[a - a/2*2]", 1},
	    {"r[-(b)*(-b)]", 9},
	    {"r[((((((((((((((((((((((((((((((((1))))))))))))))))))))))))))))))))]", 1},  // 32 deep
		// Only parentheses and unary signs nest: a second term or factor at the deepest level is
		// no deeper than the first.
	    {"r[((((((((((((((((((((((((((((((((1+2))))))))))))))))))))))))))))))))]", 3},
	    {"r[((((((((((((((((((((((((((((((((2*3))))))))))))))))))))))))))))))))]", 6},
	};
	int failures = 0;
	for (size_t c = 0; c < sizeof values / sizeof values[0]; c++) {
		char text[1024];
		snprintf(text, sizeof text, format, values[c].reference);
		sm_error err = {SM_OK, ""};
		sm_document* doc = parse(text, &err);
		sm_model* m = NULL;
		sm_spring_def spring = sm_default_spring_def();
		if (doc != NULL && sm_document_build(doc, &m, NULL) == SM_OK)
			sm_model_get_spring(m, sm_model_spring_count(m) - 1, &spring);
		if (doc == NULL || spring.b != 1 + values[c].position) {
			printf("  %s: %s, particle %d, expected %d\n", values[c].reference,
			       doc == NULL ? err.message : "loaded", (int)spring.b, (int)(1 + values[c].position));
			failures++;
		}
		if (doc != NULL) {
			const uint32_t uses = sm_document_parameter_uses(doc, sm_document_parameter_index(doc, "a"));
			const bool named = strchr(values[c].reference, 'a') != NULL;
			ENSURE(uses == (named ? (uint32_t)SM_PARAMETER_PARTICLE_REFERENCES : 0u));
			ENSURE(sm_document_parameter_uses(doc, sm_document_parameter_index(doc, "k")) ==
			       SM_PARAMETER_CONSTANTS);
		}
		sm_model_destroy(m);
		sm_document_destroy(doc);
	}
	ENSURE(failures == 0);
	static const char* const form =
	    "a structure reference is name[i], name[row, column] or name[row, column, layer]";
	static const struct {
		const char* reference;
		sm_status status;
		const char* message;  // after "test.json: springs[0].b: \"<reference>\""
	} refusals[] = {
	    {"r[c]", SM_ERROR_NOT_FOUND, ": no parameter named \"c\""},
	    {"r[h]", SM_ERROR_SCHEMA, ": parameter h = 0.5 is not a whole number within 2^31"},
	    {"r[a/z]", SM_ERROR_SCHEMA, ": division by zero (with parameter a = 7 and parameter z = 0)"},
	    {"r[big*big]", SM_ERROR_SCHEMA,
		 ": a value beyond 2^31 in magnitude (with parameter big = 2147483648)"},
	    {"r[big+1]", SM_ERROR_SCHEMA, ": a value beyond 2^31 in magnitude (with parameter big = 2147483648)"},
	    {"r[2147483649]", SM_ERROR_SCHEMA, ": a value beyond 2^31 in magnitude"},
	    {"r[99999999999999999999]", SM_ERROR_SCHEMA, ": a value beyond 2^31 in magnitude"},
	    {"r[-big - 1]", SM_ERROR_SCHEMA,
		 ": a value beyond 2^31 in magnitude (with parameter big = 2147483648)"},
	    {"r[huge - 2147483640]", SM_ERROR_SCHEMA,
		 ": parameter huge = 2147483649 is not a whole number within 2^31"},
	    {"r[a*b]", SM_ERROR_PARTICLE_INDEX,
		 " is outside structure r ([0] to [100]) (with parameter a = 7 and parameter b = -3)"},
	    {"r[a-]", SM_ERROR_SCHEMA, ": a number, a parameter or '(' expected; "},
	    {"r[(a]", SM_ERROR_SCHEMA, ": ')' expected; "},
	    {"r[a)]", SM_ERROR_SCHEMA, ": an operator, ',' or ']' expected; "},
	    {"r[a b]", SM_ERROR_SCHEMA, ": an operator, ',' or ']' expected; "},
	    {"r[2a]", SM_ERROR_SCHEMA, ": an operator, ',' or ']' expected; "},
	    {"r[]", SM_ERROR_SCHEMA, ": a number, a parameter or '(' expected; "},
	    {"r[1e2]", SM_ERROR_SCHEMA, ": an operator, ',' or ']' expected; "},
	    {"r[a,]", SM_ERROR_SCHEMA, ": a number, a parameter or '(' expected; "},
	    {"r[1,2,3,4]", SM_ERROR_SCHEMA, ": "},
	    {"r[1]]", SM_ERROR_SCHEMA, ": "},
	    {"r[(((((((((((((((((((((((((((((((((1)))))))))))))))))))))))))))))))))]", SM_ERROR_SCHEMA,
		 ": nested more than 32 deep; "},
	    {"r[---------------------------------1]", SM_ERROR_SCHEMA, ": nested more than 32 deep; "},
	};
	for (size_t c = 0; c < sizeof refusals / sizeof refusals[0]; c++) {
		char text[1024], expected[400];
		snprintf(text, sizeof text, format, refusals[c].reference);
		// A syntax error ends with the form of a reference.
		const char* message = refusals[c].message;
		const size_t length = strlen(message);
		snprintf(expected, sizeof expected, "test.json: springs[0].b: \"%s\"%s%s", refusals[c].reference,
		         message, message[length - 1] == ' ' ? form : "");
		failures += !refused_as(text, refusals[c].reference, refusals[c].status, expected);
	}
	ENSURE(failures == 0);
	// A name in an index is shown as the file's other names and keys are (docs/model-format.md,
	// test_messages_quote_text): whole up to 80 bytes, longer ones cut there with "..." after the
	// quote; the reference around it, quoted first, is cut at 80 bytes too ("r[" and 78 letters).
	// An unknown name of 80 and of 81 bytes, and a 90-byte parameter that is not a whole number.
	char a80[81], a78[79];
	memset(a80, 'a', 80);
	a80[80] = '\0';
	memcpy(a78, a80, 78);
	a78[78] = '\0';
	for (int length = 80; length <= 81; length++) {
		char reference[100], text[1024], expected[400];
		snprintf(reference, sizeof reference, "r[%s%s]", a80, length > 80 ? "a" : "");
		snprintf(text, sizeof text, format, reference);
		snprintf(expected, sizeof expected,
		         "test.json: springs[0].b: \"r[%s\"...: no parameter named \"%s\"%s", a78, a80,
		         length > 80 ? "..." : "");
		ENSURE(refused_as(text, reference, SM_ERROR_NOT_FOUND, expected));
	}
	char h90[91], h78[79], long_text[1024], long_expected[400];
	memset(h90, 'h', 90);
	h90[90] = '\0';
	memcpy(h78, h90, 78);
	h78[78] = '\0';
	snprintf(
	    long_text, sizeof long_text,
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"%s\": 0.5}, \"structures\": [{\"type\": \"rope\","
	    " \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 3}], \"fixed\": [\"r[%s]\"]}",
	    h90, h90);
	snprintf(long_expected, sizeof long_expected,
	         "test.json: fixed[0]: \"r[%s\"...: parameter %.80s... = 0.5 is not a whole number within 2^31",
	         h78, h90);
	ENSURE(refused_as(long_text, "r[h90]", SM_ERROR_SCHEMA, long_expected));
	// Parameters of 200 bytes, the longest name, are cut as well where a message lists them
	// after the reference, on loading and on a change refused, which names them once: the
	// message stays whole (its closing parenthesis) within SM_ERROR_MESSAGE_CAPACITY.
	char names[3][201], cut[3][81], many_text[2048], many_expected[SM_ERROR_MESSAGE_CAPACITY];
	for (int k = 0; k < 3; k++) {
		memset(names[k], 'a' + k, 200);
		names[k][200] = '\0';
		memcpy(cut[k], names[k], 80);
		cut[k][80] = '\0';
	}
	snprintf(
	    many_text, sizeof many_text,
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"%s\": 1, \"%s\": 1, \"%s\": %d},"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0],"
	    " \"segments\": 3}], \"fixed\": [\"r[%s * %s * %s]\"]}",
	    names[0], names[1], names[2], 5, names[0], names[1], names[2]);
	snprintf(
	    many_expected, sizeof many_expected,
	    "test.json: fixed[0]: \"r[%.78s\"... is outside structure r ([0] to [3]) (with parameter %s... = 1, "
	    "parameter %s... = 1 and parameter %s... = 5)",
	    names[0], cut[0], cut[1], cut[2]);
	ENSURE(refused_as(many_text, "r[a200 * b200 * c200]", SM_ERROR_PARTICLE_INDEX, many_expected));
	many_text[strstr(many_text, ": 5}") - many_text + 2] = '1';
	sm_error err = {SM_OK, ""};
	sm_document* many = parse_valid(many_text, &err);
	ENSURE(many != NULL);
	ENSURE_STATUS(sm_document_set_parameter(many, 2, 5, &err), SM_ERROR_PARTICLE_INDEX);
	if (strcmp(err.message, many_expected) != 0)
		printf("  \"%s\"\n  expected \"%s\"\n", err.message, many_expected);
	ENSURE(strcmp(err.message, many_expected) == 0);
	sm_document_destroy(many);
	// Later messages on the element name the parameters of its references too: z puts the
	// spring's end a on p, j both ends on one particle.
	static const char* const later =
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"z\": 0, \"k\": 2, \"j\": 1},"
	    " \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 0]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 4}],"
	    " \"springs\": [{\"a\": \"r[%s]\", \"b\": \"%s\", \"strain_stiffness\": \"k\"}]}";
	char text[1024];
	snprintf(text, sizeof text, later, "z", "p");
	ENSURE(
	    refused_as(text, "r[z] on p", SM_ERROR_ZERO_REST_LENGTH,
		           "test.json: springs[0]: per-strain stiffness needs a rest length > 0 (rest length is 0) "
		           "(with parameter z = 0 and parameter k = 2)"));
	snprintf(text, sizeof text, later, "j", "r[j * 1]");
	ENSURE(refused_as(
	    text, "r[j] to itself", SM_ERROR_SELF_SPRING,
	    "test.json: springs[0]: connects particle 2 (\"r[1]\") to itself (a and b are the same particle) "
	    "(with parameter j = 1)"));
	return 0;
}

// References that name a grid by its size parameter follow it when it changes: a port at the
// middle of an n x n sheet, the two far corners fixed, a spring to the end of a rope of m
// segments, and a probe on the rope's particle n + 1 (m = n + 1 keeps it the rope's end). n = 5, 8
// and 7 put the middle at 2, 4 and 3 (n / 2 rounds down).
static int test_references_follow_their_parameters(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"n\": 5, \"m\": 6},"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": \"n\", \"nv\": \"n\","
	    "   \"structural\": {\"strain_stiffness\": 10}},"
	    "  {\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 1], \"end\": [1, 0, 1], \"segments\": \"m\"}],"
	    " \"springs\": [{\"a\": \"c[n - 1, n / 2]\", \"b\": \"r[m]\", \"stiffness\": 1}],"
	    " \"fixed\": [\"c[n-1, 0]\", \"c[n - 1, n - 1]\"],"
	    " \"ports\": [{\"name\": \"middle\", \"particle\": \"c[n/2, n/2]\", \"kind\": \"force\"},"
	    "  {\"name\": \"end\", \"particle\": \"r[n + 1]\", \"kind\": \"probe\"}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const int32_t n = sm_document_parameter_index(doc, "n"), m = sm_document_parameter_index(doc, "m");
	ENSURE(sm_document_parameter_uses(doc, n) == (SM_PARAMETER_COUNTS | SM_PARAMETER_PARTICLE_REFERENCES));
	ENSURE(sm_document_parameter_uses(doc, m) == (SM_PARAMETER_COUNTS | SM_PARAMETER_PARTICLE_REFERENCES));
	static const int sizes[] = {5, 8, 7};
	for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
		const int size = sizes[k], middle = size / 2;
		const double values[2] = {size, size + 1};
		ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
		char name[64];
		snprintf(name, sizeof name, "c[%d,%d]", middle, middle);
		ENSURE(sm_document_port(doc, 0).particle == sm_document_particle_index(doc, name));
		sm_model* model = NULL;
		ENSURE_STATUS(sm_document_build(doc, &model, NULL), SM_OK);
		ENSURE(count_fixed(model) == 2);
		snprintf(name, sizeof name, "c[%d,0]", size - 1);
		ENSURE(sm_model_free_index(model, sm_document_particle_index(doc, name)) == -1);
		snprintf(name, sizeof name, "c[%d,%d]", size - 1, size - 1);
		ENSURE(sm_model_free_index(model, sm_document_particle_index(doc, name)) == -1);
		sm_spring_def spring;
		sm_model_get_spring(model, sm_model_spring_count(model) - 1, &spring);
		snprintf(name, sizeof name, "c[%d,%d]", size - 1, middle);
		ENSURE(spring.a == sm_document_particle_index(doc, name));
		snprintf(name, sizeof name, "r[%d]", size + 1);
		ENSURE(spring.b == sm_document_particle_index(doc, name));
		sm_model_destroy(model);
	}
	// A value that puts a reference outside its structure is refused, and the document keeps m = 8.
	ENSURE_STATUS(sm_document_set_parameter(doc, m, 3, &err), SM_ERROR_PARTICLE_INDEX);
	ENSURE(
	    strstr(
	        err.message,
	        "ports[1].particle: \"r[n + 1]\" is outside structure r ([0] to [3]) (with parameter n = 7)") !=
	    NULL);
	ENSURE(sm_document_parameter_value(doc, m) == 8.0 &&
	       sm_document_port(doc, 1).particle == sm_document_particle_index(doc, "r[8]"));
	sm_document_destroy(doc);
	return 0;
}

// A name has 1 to 200 bytes: a particle named with 200 bytes loads and is found by that name; one
// of 201 is refused, naming the rule.
static int test_names_of_200_bytes(void)
{
	char name[202], text[400];
	memset(name, 'n', 200);
	name[200] = '\0';
	const char* format =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"%s\", \"position\": [0, 0, 0]}]}";
	snprintf(text, sizeof text, format, name);
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	ENSURE(sm_document_particle_index(doc, name) == 0);
	sm_document_destroy(doc);
	name[200] = 'n';
	name[201] = '\0';
	snprintf(text, sizeof text, format, name);
	ENSURE(parse(text, &err) == NULL && err.status == SM_ERROR_SCHEMA);
	ENSURE(strcmp(err.message,
	              "test.json: particles[0].name: a name must have 1 to 200 bytes (this one has 201)") == 0);
	return 0;
}

// The "simulation" and "fmu" settings: a file without them gets the defaults of the tables in
// docs/model-format.md, and a file that gives each setting gets it. "atol" sets both absolute
// tolerances, and its least value, 1e-150, is allowed ("at least"); "atol_position" or
// "atol_velocity" beside it wins for its own; "max_step": 0 is allowed (no limit). A simulation
// takes the default settings, and refuses max_steps 0, which the file therefore refuses where
// it is written.
static int test_settings_and_their_defaults(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse(TWO_PARTICLES "}", &err);
	ENSURE(doc != NULL);
	sm_document_settings s = sm_document_get_settings(doc);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_simulation* sim = sm_simulation_create(m, &s.solver, &err);
	ENSURE(sim != NULL);
	sm_simulation_destroy(sim);
	sm_simulation_def no_steps = s.solver;
	no_steps.max_steps = 0;
	ENSURE(sm_simulation_create(m, &no_steps, &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);
	sm_model_destroy(m);
	ENSURE(s.stop_time == 1.0 && s.output_interval == 0.01 && s.particle_variables);
	ENSURE(s.solver.relative_tolerance == 1e-6 && s.solver.absolute_tolerance_position == 1e-8 &&
	       s.solver.absolute_tolerance_velocity == 1e-6);
	ENSURE(s.solver.method == SM_METHOD_BDF && s.solver.solver == SM_SOLVER_AUTO &&
	       s.solver.jacobian == SM_JACOBIAN_EXACT);
	ENSURE(s.solver.max_step == 0.0 && s.solver.max_steps == 100000 && s.solver.restart_on_input_change &&
	       s.solver.stability_limit_detection);
	sm_document_destroy(doc);

	doc = parse_valid(
	    TWO_PARTICLES
	    ", \"simulation\": {\"stop_time\": 3, \"output_interval\": 0.5, \"rtol\": 0.001,"
	    " \"atol\": 1e-150, \"method\": \"adams\", \"solver\": \"klu\", \"jacobian\": \"definite\","
	    " \"max_step\": 0, \"max_steps\": 7, \"input_changes\": \"keep\", \"stability_limit_detection\": false},"
	    " \"fmu\": {\"particle_variables\": true}}",
	    &err);
	ENSURE(doc != NULL);
	s = sm_document_get_settings(doc);
	ENSURE(s.stop_time == 3.0 && s.output_interval == 0.5 && s.particle_variables);
	ENSURE(s.solver.relative_tolerance == 0.001 && s.solver.absolute_tolerance_position == 1e-150 &&
	       s.solver.absolute_tolerance_velocity == 1e-150);
	ENSURE(s.solver.method == SM_METHOD_ADAMS && s.solver.solver == SM_SOLVER_KLU &&
	       s.solver.jacobian == SM_JACOBIAN_DEFINITE);
	ENSURE(s.solver.max_step == 0.0 && s.solver.max_steps == 7 && !s.solver.restart_on_input_change &&
	       !s.solver.stability_limit_detection);
	sm_document_destroy(doc);

	doc = parse(TWO_PARTICLES
	            ", \"simulation\": {\"method\": \"bdf\", \"jacobian\": \"exact\", \"max_step\": 0.25}}",
	            &err);
	ENSURE(doc != NULL);
	s = sm_document_get_settings(doc);
	ENSURE(s.solver.method == SM_METHOD_BDF && s.solver.jacobian == SM_JACOBIAN_EXACT &&
	       s.solver.max_step == 0.25);
	// The settings the object leaves out keep their defaults.
	ENSURE(s.solver.restart_on_input_change && s.solver.stability_limit_detection &&
	       s.solver.solver == SM_SOLVER_AUTO && s.solver.max_steps == 100000);
	sm_document_destroy(doc);

	// atol_position or atol_velocity beside atol wins for its own tolerance, in either order.
	doc = parse(TWO_PARTICLES ", \"simulation\": {\"atol_position\": 1e-9, \"atol\": 1e-3}}", &err);
	ENSURE(doc != NULL);
	s = sm_document_get_settings(doc);
	ENSURE(s.solver.absolute_tolerance_position == 1e-9 && s.solver.absolute_tolerance_velocity == 1e-3);
	sm_document_destroy(doc);
	doc = parse(TWO_PARTICLES ", \"simulation\": {\"atol\": 1e-3, \"atol_velocity\": 1e-5}}", &err);
	ENSURE(doc != NULL);
	s = sm_document_get_settings(doc);
	ENSURE(s.solver.absolute_tolerance_position == 1e-3 && s.solver.absolute_tolerance_velocity == 1e-5);
	sm_document_destroy(doc);
	return 0;
}

// A spring group whose stiffness alone, or damping alone, is a parameter creates its springs while
// the parameter is 0 (docs: "parameters never change which springs exist"), and setting the
// parameter then acts on them. Rope of 3 segments: 3 structural and 2 bending springs.
static int test_groups_with_one_parameter_keep_their_springs(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 0, \"c\": 0}, \"structures\":"
	    " [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [3, 0, 0], \"segments\": 3,"
	    " \"structural\": {\"stiffness\": \"k\"}, \"bending\": {\"stiffness\": 0, \"damping\": \"c\"}}]}",
	    &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_spring_count(m) == 3 + 2);
	sm_model_destroy(m);
	const double values[2] = {40.0, 0.5};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(sm_model_spring_count(m) == 3 + 2);
	int structural = 0, bending = 0;
	for (int32_t k = 0; k < sm_model_spring_count(m); k++) {
		sm_spring_def d;
		double ks, kd;
		sm_model_get_spring(m, k, &d);
		sm_model_spring_constants(m, k, NULL, &ks, &kd);
		if (d.b - d.a == 1)
			structural += ks == 40.0 && kd == 0.0;
		else
			bending += d.b - d.a == 2 && ks == 0.0 && kd == 0.5;
	}
	ENSURE(structural == 3 && bending == 2);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// Saving keeps each group's parameter on that group's springs, for every kind of structure and
// group: the saved file loads to the same model, and after the same new parameter values in both
// documents still does (docs: "every parameter reference kept"). Every group has its own
// parameter and value, so a spring written with another group's parameter differs.
static int test_saved_groups_keep_their_parameters(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"g\", \"parameters\": {\"a\": 1, \"b\": 2, \"c\": 3, \"d\": 4, \"e\": 5, \"f\": 6,"
	    " \"g\": 7, \"h\": 8, \"i\": 9, \"j\": 10},"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 3,"
	    "   \"structural\": {\"strain_stiffness\": \"a\"}, \"bending\": {\"stiffness\": \"b\"}},"
	    "  {\"type\": \"sheet\", \"name\": \"s\", \"origin\": [0, 1, 0], \"nu\": 3, \"nv\": 3, \"structural\": {\"stiffness\": \"c\"},"
	    "   \"shear\": {\"damping\": \"d\"}, \"bend\": {\"strain_stiffness\": \"e\"}},"
	    "  {\"type\": \"block\", \"name\": \"k\", \"origin\": [0, 3, 0], \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2, \"nw\": 2,"
	    "   \"edge\": {\"stiffness\": \"f\"}, \"face_diagonal\": {\"strain_damping\": \"g\"}, \"body_diagonal\": {\"stiffness\": \"h\"}},"
	    "  {\"type\": \"mesh\", \"name\": \"m\", \"vertices\": [[0, 5, 0], [1, 5, 0], [0, 6, 0], [1, 6, 0]],"
	    "   \"triangles\": [[0, 1, 3], [0, 3, 2]], \"edge\": {\"stiffness\": \"i\"}, \"bend\": {\"damping\": \"j\"}}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	const double values[10] = {11, 12, 13, 14, 15, 16, 17, 18, 19, 20};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameters(again, values, &err), SM_OK);
	ENSURE(same_document(doc, again) == 0);
	for (int32_t k = 0; k < 10; k++)
		ENSURE(sm_document_parameter_uses(again, k) == SM_PARAMETER_CONSTANTS);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// "fixed" holds every particle it lists and every particle in a box, bounds included; a fixed
// particle starts at rest whatever velocity the file gives it (docs: velocity "ignored for a
// fixed particle"), while a free one keeps its own.
static int test_fixed_particles_start_at_rest(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"velocity\":"
	    " [1, 0, 0]}, {\"position\": [1, 0, 0], \"velocity\": [0, 2, 0]}, {\"position\": [2, 0, 0]},"
	    " {\"position\": [3, 0, 0], \"velocity\": [0, 0, 3]}],"
	    " \"fixed\": [{\"min\": [1, 0, 0], \"max\": [2, 0, 0]}, 0]}",
	    &err);
	ENSURE(doc != NULL);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	double v[12];
	sm_model_initial_state(m, NULL, v);
	for (int32_t i = 0; i < 3; i++) {
		ENSURE(sm_model_free_index(m, i) == -1);
		ENSURE(v[3 * i] == 0.0 && v[3 * i + 1] == 0.0 && v[3 * i + 2] == 0.0);
	}
	ENSURE(sm_model_free_count(m) == 1 && sm_model_free_index(m, 3) == 0);
	ENSURE(v[9] == 0.0 && v[10] == 0.0 && v[11] == 3.0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// An initial state set on a document (sm_document_set_initial_state) gives the built model its
// positions and velocities, and stays through a parameter change that keeps the particles (the
// constant changes, the state and the file's rest lengths stay); a parameter value that would
// change the number of particles, fewer or more, is refused, and so is a non-finite state, each
// leaving the document as it was. Particles: a (fixed), b, then the rope's n + 1 = 3.
static int test_initial_state_through_parameter_changes(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 10, \"n\": 2},"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true},"
	    " {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 1], \"end\": [1, 0, 1],"
	    " \"segments\": \"n\"}], \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": \"k\"}]}",
	    &err);
	ENSURE(doc != NULL);
	const double x[15] = {0, 0, 0, 1.5, 0, 0, 0, 0, 2, 0.5, 0, 2, 1, 0, 2};
	const double v[15] = {0, 0, 0, 0, 0.25, 0, 0, 0, 0, 0, 0, 0, 0, 0, -1};
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, v, &err), SM_OK);
	const int32_t k = sm_document_parameter_index(doc, "k"), n = sm_document_parameter_index(doc, "n");
	for (int pass = 0; pass < 2; pass++) {
		sm_model* m = NULL;
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE(sm_model_particle_count(m) == 5);
		double xm[15], vm[15];
		sm_model_initial_state(m, xm, vm);
		ENSURE(memcmp(xm, x, sizeof x) == 0 && memcmp(vm, v, sizeof v) == 0);
		double l0, ks;
		sm_model_spring_constants(m, sm_model_spring_count(m) - 1, &l0, &ks, NULL);
		ENSURE(l0 == 1.0 && ks == (pass == 0 ? 10.0 : 20.0));
		sm_model_destroy(m);
		if (pass == 0)
			ENSURE_STATUS(sm_document_set_parameter(doc, k, 20.0, &err), SM_OK);
	}
	ENSURE_STATUS(sm_document_set_parameter(doc, n, 1.0, &err), SM_ERROR_TOPOLOGY);
	ENSURE_STATUS(sm_document_set_parameter(doc, n, 3.0, &err), SM_ERROR_TOPOLOGY);
	ENSURE(sm_document_parameter_value(doc, n) == 2.0);
	double bad[15];
	memcpy(bad, x, sizeof x);
	for (int c = 0; c < 15; c++)
		bad[c] += 1.0;
	bad[14] = NAN;
	ENSURE_STATUS(sm_document_set_initial_state(doc, bad, NULL, &err), SM_ERROR_NOT_FINITE);
	// So are velocities, named by their particle.
	double fast[15] = {0.0};
	fast[7] = INFINITY;
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, fast, &err), SM_ERROR_NOT_FINITE);
	ENSURE(strcmp(err.message, "test.json: initial state of particle 2 is not finite") == 0);
	// Finite positions whose spring's length is not (the square of 1e200 m overflows) are refused
	// too: the file saved with them would not load, the loader refusing such a spring.
	memcpy(bad, x, sizeof x);
	bad[3] = 1e200;
	ENSURE_STATUS(sm_document_set_initial_state(doc, bad, NULL, &err), SM_ERROR_NOT_FINITE);
	ENSURE(strcmp(err.message,
	              "test.json: initial state: spring 0: the distance between particles 0 and 1 is too "
	              "large (its square overflows: particles joined by springs must be less than 1.3e154 "
	              "m apart)") == 0);
	ENSURE_STATUS(sm_document_set_parameter(doc, k, 30.0, &err), SM_OK);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	double xm[15], vm[15];
	sm_model_initial_state(m, xm, vm);
	ENSURE(memcmp(xm, x, sizeof x) == 0 && memcmp(vm, v, sizeof v) == 0);
	sm_model_destroy(m);
	sm_document_destroy(doc);

	// The distance counts in every direction and for every spring: the second spring of a chain
	// along x, its end moved 1e200 m up along z alone, is named with its own particles.
	doc = parse_valid("{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": "
	                  "[0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0]}, {\"name\": "
	                  "\"c\", \"position\": [2, 0, 0]}], \"springs\": [{\"a\": \"a\", \"b\": \"b\"}, {\"a\": "
	                  "\"b\", \"b\": \"c\"}]}",
	                  &err);
	ENSURE(doc != NULL);
	const double up[9] = {0, 0, 0, 1, 0, 0, 2, 0, 1e200};
	ENSURE_STATUS(sm_document_set_initial_state(doc, up, NULL, &err), SM_ERROR_NOT_FINITE);
	ENSURE(strcmp(err.message,
	              "test.json: initial state: spring 1: the distance between particles 1 and 2 is too "
	              "large (its square overflows: particles joined by springs must be less than 1.3e154 "
	              "m apart)") == 0);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_model_initial_state(m, xm, NULL);
	ENSURE(xm[6] == 2.0 && xm[8] == 0.0);  // the file's positions, the document unchanged
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// A document's counts are those of the model it builds, for every bundled model, and follow a
// parameter that changes them: the cloth of n x n particles has 2 n (n - 1) structural, 2 (n - 1)^2
// shear and 2 n (n - 2) bending springs, and its last particle is cloth[n-1,n-1].
static int test_document_counts(void)
{
	ENSURE(sm_document_particle_count(NULL) == 0 && sm_document_spring_count(NULL) == 0);
	for (int b = 0; b < BUNDLED_COUNT; b++) {
		sm_document* doc = load_bundled(bundled[b], NULL);
		ENSURE(doc != NULL);
		sm_model* m = NULL;
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE(sm_document_particle_count(doc) == sm_model_particle_count(m));
		ENSURE(sm_document_spring_count(doc) == sm_model_spring_count(m));
		sm_model_destroy(m);
		sm_document_destroy(doc);
	}
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_bundled("cloth", &err);
	ENSURE(doc != NULL);
	const int32_t n = sm_document_parameter_index(doc, "n");
	for (int32_t side = 16; side >= 10; side -= 6) {
		ENSURE_STATUS(sm_document_set_parameter(doc, n, side, &err), SM_OK);
		ENSURE(sm_document_particle_count(doc) == side * side);
		ENSURE(sm_document_spring_count(doc) ==
		       2 * side * (side - 1) + 2 * (side - 1) * (side - 1) + 2 * side * (side - 2));
		sm_model* m = NULL;
		ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
		ENSURE(sm_document_particle_count(doc) == sm_model_particle_count(m));
		ENSURE(sm_document_spring_count(doc) == sm_model_spring_count(m));
		sm_model_destroy(m);
		char last[32];
		snprintf(last, sizeof last, "cloth[%d,%d]", (int)side - 1, (int)side - 1);
		ENSURE(strcmp(sm_document_particle_name(doc, sm_document_particle_count(doc) - 1), last) == 0);
		ENSURE(sm_document_particle_name(doc, sm_document_particle_count(doc)) == NULL);
	}
	sm_document_destroy(doc);
	return 0;
}

// sm_document_set_initial_state with NULL positions drops the state set before and leaves
// nothing of it: the cloth's n, refused while the state is set, is taken again; the model built
// and the file saved are those of the file, velocities included (the state's are dropped too);
// a position the file takes from a parameter is saved as that parameter again. Velocities
// without positions are refused, keeping the state; dropping twice changes nothing.
static int test_dropping_the_initial_state(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_bundled("cloth", &err);
	sm_document* file = load_bundled("cloth", &err);
	ENSURE(doc != NULL && file != NULL);
	sm_model* from_file = NULL;
	ENSURE_STATUS(sm_document_build(file, &from_file, NULL), SM_OK);
	const int32_t count = sm_document_particle_count(doc);
	double* x = malloc(3 * (size_t)count * sizeof(double));
	double* v = calloc(3 * (size_t)count, sizeof(double));
	ENSURE(x != NULL && v != NULL);
	sm_model_initial_state(from_file, x, NULL);
	// Lowered by 0.25 m, the free particles moving at 1 m/s along x.
	for (int32_t i = 0; i < count; i++) {
		x[3 * i + 2] -= 0.25;
		v[3 * i] = sm_model_free_index(from_file, i) >= 0 ? 1.0 : 0.0;
	}
	const char* corner = sm_document_particle_name(doc, 0);
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, v, &err), SM_OK);
	const int32_t n = sm_document_parameter_index(doc, "n");
	ENSURE_STATUS(sm_document_set_parameter(doc, n, 10.0, &err), SM_ERROR_TOPOLOGY);
	ENSURE_STATUS(sm_document_set_initial_state(doc, NULL, v, &err), SM_ERROR_INVALID_ARGUMENT);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	sm_particle_def p;
	sm_model_get_particle(m, 0, &p);
	ENSURE(p.position[2] == -0.25 && p.velocity[0] == 1.0);
	sm_model_destroy(m);

	for (int pass = 0; pass < 2; pass++)
		ENSURE_STATUS(sm_document_set_initial_state(doc, NULL, NULL, &err), SM_OK);
	ENSURE(strcmp(corner, "cloth[0,0]") == 0);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	ENSURE(same_model(m, from_file) == 0);
	sm_model_destroy(m);
	char* saved = sm_document_to_json(doc, &err);
	char* saved_file = sm_document_to_json(file, &err);
	ENSURE(saved != NULL && saved_file != NULL);
	ENSURE(strcmp(saved, saved_file) == 0);
	free(saved);
	free(saved_file);
	ENSURE_STATUS(sm_document_set_parameter(doc, n, 10.0, &err), SM_OK);
	ENSURE(sm_document_particle_count(doc) == 100);
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, NULL, &err), SM_OK);
	ENSURE(sm_document_particle_count(doc) == 100);
	free(x);
	free(v);
	sm_model_destroy(from_file);
	sm_document_destroy(file);
	sm_document_destroy(doc);

	// The height of the fixed particle is the parameter h.
	doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"h\": 2},"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, \"h\"], \"fixed\": true},"
	    " {\"name\": \"b\", \"position\": [0, 0, 1]}], \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 10}]}",
	    &err);
	ENSURE(doc != NULL);
	const double hanging[6] = {0, 0, 2, 0, 0, 0.5};
	ENSURE_STATUS(sm_document_set_initial_state(doc, hanging, NULL, &err), SM_OK);
	saved = sm_document_to_json(doc, &err);
	ENSURE(saved != NULL && strstr(saved, "\"h\"]") == NULL);
	free(saved);
	ENSURE_STATUS(sm_document_set_initial_state(doc, NULL, NULL, &err), SM_OK);
	saved = sm_document_to_json(doc, &err);
	ENSURE(saved != NULL && strstr(saved, "\"position\": [0, 0, \"h\"]") != NULL);
	free(saved);
	ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "h"), 3.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &m, NULL), SM_OK);
	double xm[6];
	sm_model_initial_state(m, xm, NULL);
	ENSURE(xm[2] == 3.0 && xm[5] == 1.0);
	sm_model_destroy(m);
	sm_document_destroy(doc);
	return 0;
}

// Line and column of a syntax error are those an editor shows, at the first character of a token
// the message quotes whole (where the cursor goes to mend it: before it for a missing comma):
// columns count characters, so that a tab and a character of four UTF-8 bytes are one column
// each; lines end at LF or CR LF; and an error at the end of a text whose last line ends is at
// column 0 of the line after it, as in docs/model-format.md ("truncated.json:3:0: ']' expected
// near end of file").
static int test_syntax_error_positions(void)
{
	static const refusal cases[] = {
	    {"{\t\"springmass\": 1,\t\"name\":\t@}", SM_ERROR_SYNTAX, "test.json:1:28: invalid token near '@'"},
	    {"{\"springmass\": 1, \"name\": \"\xf0\x9f\x98\x80\" @}", SM_ERROR_SYNTAX,
		 "test.json:1:31: '}' expected near '@'"},
	    {"{\r\n\t\"springmass\": 1,\r\n\t\"name\" \"x\"}", SM_ERROR_SYNTAX,
		 "test.json:3:9: ':' expected near '\"x\"'"},
	    // A token the whole text begins with: at column 1, its first character (the parser stopped
	    // after its last, exactly as many bytes in as the token is long).
	    {"\"x\"", SM_ERROR_SYNTAX, "test.json:1:1: '[' or '{' expected near '\"x\"'"},
	    {"{\"springmass\": 1, \"name\": \"x\",\n \"particles\": [{\"position\": [0, 0, 0]}\n",
		 SM_ERROR_SYNTAX, "test.json:3:0: ']' expected near end of file"},
	    // Another value where the end of an array or object was expected: a missing comma?
	    {"{\"springmass\": 1, \"name\": \"x\",\n \"particles\": [{\"position\": [0, 0, 0]}\n \"springs\": []}",
		 SM_ERROR_SYNTAX, "test.json:3:2: ']' expected near '\"springs\"' (or a ',' before it)"},
	    {"{\"springmass\": 1 \"name\": \"x\"}", SM_ERROR_SYNTAX,
		 "test.json:1:18: '}' expected near '\"name\"' (or a ',' before it)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"gravity\": [0 0 -9.81]}", SM_ERROR_SYNTAX,
		 "test.json:1:46: ']' expected near '0' (or a ',' before it)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"gravity\": [0, 0 -9.81]}", SM_ERROR_SYNTAX,
		 "test.json:1:49: ']' expected near '-9.81' (or a ',' before it)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"gravity\": [0, 0, 0] null}", SM_ERROR_SYNTAX,
		 "test.json:1:53: '}' expected near 'null' (or a ',' before it)"},
	    // An error at a line end is at column 0 of the next line, whichever kind the line end is.
	    {"{\"springmass\": 1, \"name\": \"x\\\n\"}", SM_ERROR_SYNTAX,
		 "test.json:2:0: invalid escape near '\"x\\\\u000a'"},
	    {"{\"springmass\": 1, \"name\": \"x\\\r\n\"}", SM_ERROR_SYNTAX,
		 "test.json:2:0: invalid escape near '\"x\\\\u000d'"},
	    {"{\"springmass\": 1, \"name\": \"x\\\r\"}", SM_ERROR_SYNTAX,
		 "test.json:2:0: invalid escape near '\"x\\\\u000d'"},
	    // A byte the parser refuses where it stands (a control character in a string, one that
	    // is no UTF-8) is at its own column, not at the character before it; a line end in a
	    // string is at column 0 of the next line.
	    {"{\"springmass\": 1, \"name\": \"\xc3\xa9\t\"}", SM_ERROR_SYNTAX,
		 "test.json:1:29: control character 0x9 near '\"\xc3\xa9'"},
	    {"{\"springmass\": 1, \"name\": \"x\n\"}", SM_ERROR_SYNTAX,
		 "test.json:2:0: unexpected newline near '\"x'"},
	    {"{\"springmass\": 1, \"name\": \"x\r\n\"}", SM_ERROR_SYNTAX,
		 "test.json:2:0: control character 0xd near '\"x'"},
	    {"{\"springmass\": 1, \"name\": \"x\xff\"}", SM_ERROR_SYNTAX,
		 "test.json:1:29: unable to decode byte 0xff near '\"x'"},
	    {"{\"springmass\": 1, \"name\": \"x\x80\"}", SM_ERROR_SYNTAX,
		 "test.json:1:29: unable to decode byte 0x80 near '\"x'"},
	    {"{\"springmass\": 1,\n\xe2\x82\"name\": \"x\"}", SM_ERROR_SYNTAX,
		 "test.json:2:1: unable to decode byte 0xe2"},
	    // A token longer than the 20 bytes the parser quotes is named and placed all the same: a
	    // repeated key, a number out of range, an invalid word, and a missing comma before a key,
	    // which is quoted up to 80 bytes and cut there with "..." after the quote.
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"a_rather_long_parameter_name\": 1,"
		 " \"a_rather_long_parameter_name\": 3}}",
		 SM_ERROR_SYNTAX, "test.json:1:82: duplicate object key near '\"a_rather_long_parameter_name\"'"},
	    // 21 bytes, one more than the parser quotes.
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"abcdefghijklmnopqrs\": 1,"
		 " \"abcdefghijklmnopqrs\": 3}}",
		 SM_ERROR_SYNTAX, "test.json:1:73: duplicate object key near '\"abcdefghijklmnopqrs\"'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 1.7976931348623159e308}}",
		 SM_ERROR_SYNTAX, "test.json:1:52: real number overflow near '1.7976931348623159e308'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": -999999999999999999999}}",
		 SM_ERROR_SYNTAX, "test.json:1:52: too big negative integer near '-999999999999999999999'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": NaNaNaNaNaNaNaNaNaNaNaN}}",
		 SM_ERROR_SYNTAX, "test.json:1:52: invalid token near 'NaNaNaNaNaNaNaNaNaNaNaN'"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 1 \"a_rather_long_parameter_name\": 2}}",
		 SM_ERROR_SYNTAX,
		 "test.json:1:54: '}' expected near '\"a_rather_long_parameter_name\"' (or a ',' before it)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"k\": 1\n \"pq"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\": 2}}",
		 SM_ERROR_SYNTAX,
		 "test.json:2:2: '}' expected near '\"pq"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9"
		 "'... (or a ',' before it)"},
	};
	return count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) > 0;
}

// The edges of the character classes of docs/model-format.md: CR and FF are line breaks, like LF
// and VT, in a description and in a name; U+009F is the last control character (C1), and the
// no-break space U+00A0 after it is text that names and descriptions may hold.
static int test_line_breaks_and_controls_at_their_edges(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"a\\rb\"}", SM_ERROR_SCHEMA,
		 "test.json: description: must be one line: it has a line break, U+000D, at character 2"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"description\": \"ab\\f\"}", SM_ERROR_SCHEMA,
		 "test.json: description: must be one line: it has a line break, U+000C, at character 3"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"ab\\r\", \"position\": [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"ab\\u000d\" has a line break, U+000D, at character 3"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\\fb\", \"position\": [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"a\\u000cb\" has a line break, U+000C, at character 2"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"\xc2\xa0\\u009f\", \"position\": [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"\xc2\xa0\\u009f\" has a control character, U+009F, at character 2"},
	};
	ENSURE(count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) == 0);
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse_valid("{\"springmass\": 1, \"name\": \"x\", \"description\": \"a\xc2\xa0z\", \"particles\":"
		            " [{\"name\": \"\xc2\xa0\", \"position\": [0, 0, 0]}]}",
		            &err);
	ENSURE(doc != NULL);
	ENSURE(strcmp(sm_document_description(doc), "a\xc2\xa0z") == 0 &&
	       sm_document_particle_index(doc, "\xc2\xa0") == 0);
	sm_document_destroy(doc);
	return 0;
}

// A message escapes each of the invisible characters that reorder text or show nothing, at both
// ends of their ranges (U+061C; U+200B - U+200F; U+202A - U+202E; U+2066 - U+2069; U+FEFF), and
// shows the visible characters just outside those ranges as they are (U+061B, U+2010, U+2027,
// U+202F, U+2070, U+FF01).
static int test_messages_escape_invisible_characters(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"fixed\": [\""
		 "\xd8\x9c\xe2\x80\x8b\xe2\x80\x8f\xe2\x80\xaa\xe2\x80\xae\xe2\x81\xa6\xe2\x81\xa9\xef\xbb\xbf\"]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: fixed[0]: no particle named \"\\u061c\\u200b\\u200f\\u202a\\u202e\\u2066\\u2069\\ufeff\""},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}], \"fixed\": [\""
		 "\xd8\x9b\xe2\x80\x90\xe2\x80\xa7\xe2\x80\xaf\xe2\x81\xb0\xef\xbc\x81\"]}",
		 SM_ERROR_NOT_FOUND,
		 "test.json: fixed[0]: no particle named \""
		 "\xd8\x9b\xe2\x80\x90\xe2\x80\xa7\xe2\x80\xaf\xe2\x81\xb0\xef\xbc\x81\""},
	};
	return count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) > 0;
}

// sm_text_for_terminal shows text as the messages do, and SM_TERMINAL_TEXT_CAPACITY is room
// enough for the widest case: each byte a control character, 6 bytes as \u0001. A byte that
// begins no character is \xNN; the tab is escaped, characters beyond ASCII stay as they are.
static int test_text_for_terminal(void)
{
	static const struct {
		const char* text;
		const char* shown;
	} cases[] = {
	    {"", ""},
	    {"plain \xc3\xa9t\xc3\xa9", "plain \xc3\xa9t\xc3\xa9"},
	    {"\x01\x02\x1b\x7f", "\\u0001\\u0002\\u001b\\u007f"},
	    {"a\tb\nc", "a\\u0009b\\u000ac"},
	    {"left \xe2\x80\xae right \xef\xbb\xbf", "left \\u202e right \\ufeff"},
	    // The word joiner and the invisible operators have no width either (U+2065 is unassigned).
	    {"a\xe2\x81\xa0"
		 "b\xe2\x81\xa4"
		 "c\xe2\x81\xa5",
		 "a\\u2060b\\u2064c\xe2\x81\xa5"},
	    {"bad \xff\xc3", "bad \\xff\\xc3"},
	    // Characters of each length at the ends of their ranges stay as they are; a surrogate, a
	    // code point past U+10FFFF and a first byte of F8 (no character begins so) are \xNN.
	    {"\xc2\x80 \xe0\xa0\x80 \xf0\x90\x80\x80 \xf4\x8f\xbf\xbf",
		 "\\u0080 \xe0\xa0\x80 \xf0\x90\x80\x80 \xf4\x8f\xbf\xbf"},
	    {"\xed\xbf\xbf \xf4\x90\x80\x80 \xf8\x90\x80\x80",
		 "\\xed\\xbf\\xbf \\xf4\\x90\\x80\\x80 \\xf8\\x90\\x80\\x80"},
	    {"\"quoted\" \\", "\"quoted\" \\"},
	};
	for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
		const size_t capacity = SM_TERMINAL_TEXT_CAPACITY(strlen(cases[k].text));
		char* out = malloc(capacity);
		ENSURE(out != NULL);
		memset(out, '#', capacity);
		sm_text_for_terminal(out, cases[k].text);
		const bool same = strcmp(out, cases[k].shown) == 0 && strlen(out) < capacity;
		free(out);
		ENSURE(same);
	}
	// The widest case fills the capacity to its last byte.
	char controls[40], out[SM_TERMINAL_TEXT_CAPACITY(sizeof controls - 1)];
	memset(controls, '\x01', sizeof controls - 1);
	controls[sizeof controls - 1] = '\0';
	sm_text_for_terminal(out, controls);
	ENSURE(strlen(out) == sizeof out - 1 && strncmp(out + sizeof out - 7, "\\u0001", 6) == 0);
	// No text (the name or description of no document, NULL) shows as the empty text, and no
	// room to write to gets nothing.
	sm_text_for_terminal(out, sm_document_description(NULL));
	ENSURE(out[0] == '\0');
	sm_text_for_terminal(NULL, "name");
	return 0;
}

// Every status has its own text (base.h gives "particle index out of range" for
// SM_ERROR_PARTICLE_INDEX), and none is the text of a value that names no status, which is
// still a text a message can print.
static int test_status_texts(void)
{
	ENSURE(strcmp(sm_status_string(SM_ERROR_PARTICLE_INDEX), "particle index out of range") == 0);
	const char* unknown = sm_status_string(SM_STATUS_COUNT);
	ENSURE(unknown != NULL && unknown[0] != '\0');
	for (int a = 0; a < SM_STATUS_COUNT; a++) {
		const char* text = sm_status_string((sm_status)a);
		ENSURE(text != NULL && text[0] != '\0' && strcmp(text, unknown) != 0);
		for (int b = 0; b < a; b++)
			ENSURE(strcmp(text, sm_status_string((sm_status)b)) != 0);
	}
	return 0;
}

// Per-section constants in a model file (docs/model-format.md): a sheet's groups take
// "section_stiffness" [N/m] and "section_damping" [N s/m] and give each spring its section; the
// canonical form writes the springs with their sections and the parameters they came from, so
// that it reads back to the same model and a new parameter value acts on it as on the original.
// A single spring gives its own "section"; a rope, which has none, is refused.
static int test_per_section_constants_in_a_model_file(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"membrane\", \"parameters\": {\"Y\": 300, \"eta\": 0.5},"
	    " \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 1]}, {\"name\": \"q\", \"position\": [0, 0, 3]}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": \"q\", \"section_stiffness\": \"Y\", \"section\": 0.25}],"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"edge_u\": [2, 0, 0], \"nu\": 5, \"nv\": 3,"
	    "  \"mass_distribution\": \"lumped\","
	    "  \"structural\": {\"section_stiffness\": \"Y\", \"section_damping\": \"eta\"},"
	    "  \"shear\": {\"section_stiffness\": 100}}]}";
	sm_error err;
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	// The sheet's springs come first: its first structural spring, along its edge
	// (row 0) from (0, 0) to (0.5, 0), stands for half a cell of 0.5 m x 0.5 m: section 0.125 m^2
	// over 0.5 m, ks = 300 x 0.25 / 0.5; the single spring, last, ks = 300 x 0.25 / 2.
	double l0, ks, kd;
	ENSURE_STATUS(sm_model_spring_constants(model, 0, &l0, &ks, &kd), SM_OK);
	ENSURE_NEAR(ks, 300.0 * 0.25 / 0.5, 1e-12);
	ENSURE_NEAR(kd, 0.5 * 0.25 / 0.5, 1e-15);
	const int32_t last = sm_model_spring_count(model) - 1;
	ENSURE_STATUS(sm_model_spring_constants(model, last, &l0, &ks, &kd), SM_OK);
	ENSURE(l0 == 2.0 && ks == 300.0 * 0.25 / 2.0 && kd == 0.0);
	// Lumped masses: 8 cells of 1/8 kg, a corner a quarter of one.
	sm_particle_def corner;
	ENSURE_STATUS(sm_model_get_particle(model, sm_document_particle_index(doc, "s[0,0]"), &corner), SM_OK);
	ENSURE(corner.mass == 1.0 / 32.0);
	sm_model_destroy(model);

	char* json = sm_document_to_json(doc, &err);
	ENSURE(json != NULL);
	ENSURE(strstr(json, "\"section_stiffness\": \"Y\"") != NULL &&
	       strstr(json, "\"section_damping\": \"eta\"") != NULL);
	sm_document* again = parse_valid(json, &err);
	free(json);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	const int32_t y = sm_document_parameter_index(doc, "Y");
	ENSURE_STATUS(sm_document_set_parameter(doc, y, 600.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameter(again, y, 600.0, &err), SM_OK);
	ENSURE(same_document(doc, again) == 0);
	ENSURE_STATUS(sm_document_build(again, &model, &err), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(model, 0, &l0, &ks, &kd), SM_OK);
	ENSURE_NEAR(ks, 600.0 * 0.25 / 0.5, 1e-12);
	sm_model_destroy(model);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	// A single spring's section from a parameter, with only its damping per section: saved as
	// the parameter, so that a new value acts on the saved document too (w = 1 doubles kd).
	const char* damped =
	    "{\"springmass\": 1, \"name\": \"d\", \"parameters\": {\"w\": 0.5},"
	    " \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [2, 0, 0]}],"
	    " \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": 5, \"section_damping\": 2, \"section\": \"w\"}]}";
	doc = parse_valid(damped, &err);
	ENSURE(doc != NULL);
	json = sm_document_to_json(doc, &err);
	ENSURE(json != NULL && strstr(json, "\"section\": \"w\"") != NULL);
	again = parse_valid(json, &err);
	free(json);
	ENSURE(again != NULL && same_document(doc, again) == 0);
	ENSURE_STATUS(sm_document_set_parameter(again, 0, 1.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(again, &model, &err), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(model, 0, &l0, &ks, &kd), SM_OK);
	ENSURE(ks == 5.0 && kd == 2.0 * 1.0 / 2.0);
	sm_model_destroy(model);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	// Lumped masses of a rope (4 segments, 2 kg: 0.25 and 0.5 kg) and of a block (3 x 3 x 3,
	// 8 kg: an eighth of a 1 kg cell at a corner) from a file.
	const char* lumped =
	    "{\"springmass\": 1, \"name\": \"l\", \"structures\": ["
	    " {\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 4,"
	    "  \"mass\": 2, \"mass_distribution\": \"lumped\", \"structural\": {\"strain_stiffness\": 10}},"
	    " {\"type\": \"block\", \"name\": \"b\", \"origin\": [0, 2, 0], \"size\": [1, 1, 1], \"nu\": 3, \"nv\": 3,"
	    "  \"nw\": 3, \"mass\": 8, \"mass_distribution\": \"lumped\", \"edge\": {\"strain_stiffness\": 10}}]}";
	doc = parse_valid(lumped, &err);
	ENSURE(doc != NULL);
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	static const char* const names[3] = {"r[0]", "r[1]", "b[0,0,0]"};
	static const double masses[3] = {0.25, 0.5, 0.125};
	for (int k = 0; k < 3; k++) {
		sm_particle_def particle;
		ENSURE_STATUS(sm_model_get_particle(model, sm_document_particle_index(doc, names[k]), &particle),
		              SM_OK);
		ENSURE_NEAR(particle.mass, masses[k], 1e-15);
	}
	sm_model_destroy(model);
	sm_document_destroy(doc);

	static const struct {
		const char* text;
		const char* message;
	} refused[] = {
	    {"{\"springmass\": 1, \"name\": \"r\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"segments\": 2,"
		 " \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"structural\": {\"section_stiffness\": 5}}]}",
		 "rope: structural stiffness per section: a rope has no cross-section (give it per strain)"},
	    {"{\"springmass\": 1, \"name\": \"r\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"section_stiffness\": 5}]}",
		 "springs[0]: per-section constants need the spring's \"section\""},
	    {"{\"springmass\": 1, \"name\": \"r\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"strain_stiffness\": 5, \"section\": 1}]}",
		 "springs[0]: \"section\" goes with \"section_stiffness\" or \"section_damping\""},
	    {"{\"springmass\": 1, \"name\": \"r\", \"particles\": [{\"position\": [0, 0, 0]}, {\"position\": [1, 0, 0]}],"
		 " \"springs\": [{\"a\": 0, \"b\": 1, \"section_damping\": 5, \"section\": 0}]}",
		 "springs[0].section"},
	    {"{\"springmass\": 1, \"name\": \"r\", \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"nu\": 2,"
		 " \"nv\": 2, \"mass_distribution\": \"area\"}]}",
		 "structures[0].mass_distribution: must be \"even\" or \"lumped\""},
	};
	for (size_t k = 0; k < sizeof refused / sizeof refused[0]; k++) {
		sm_document* bad = parse(refused[k].text, &err);
		sm_model* m = NULL;
		if (bad != NULL) {
			ENSURE(sm_document_build(bad, &m, &err) != SM_OK);
			sm_document_destroy(bad);
		}
		if (strstr(err.message, refused[k].message) == NULL)
			printf("  case %zu: %s\n", k, err.message);
		ENSURE(strstr(err.message, refused[k].message) != NULL);
	}
	return 0;
}

// Every function that takes an sm_error fills it on success too (base.h): SM_OK and an empty
// message, so that a report left from an earlier failure is never read as this call's. And the
// names of values outside an enum are "unknown", never a valid name.
static void make_stale(sm_error* err)
{
	err->status = SM_ERROR_NOT_FINITE;
	snprintf(err->message, sizeof err->message, "left from an earlier call");
}

static bool cleared(const sm_error* err)
{
	return err->status == SM_OK && err->message[0] == '\0';
}

static int test_error_reports_are_filled_on_success(void)
{
	sm_error err;
	make_stale(&err);
	sm_document* doc = load_bundled("two_mass_chain", &err);
	ENSURE(doc != NULL && cleared(&err));
	make_stale(&err);
	sm_document* parsed =
	    parse("{\"springmass\": 1, \"name\": \"one\", \"particles\": [{\"position\": [0, 0, 0]}]}", &err);
	ENSURE(parsed != NULL && cleared(&err));
	sm_document_destroy(parsed);

	sm_model* model = NULL;
	make_stale(&err);
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	ENSURE(cleared(&err));
	const int32_t np = sm_document_parameter_count(doc);
	ENSURE(np > 0);
	make_stale(&err);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, sm_document_parameter_value(doc, 0), &err), SM_OK);
	ENSURE(cleared(&err));
	double values[64];
	ENSURE(np <= 64);
	for (int32_t i = 0; i < np; i++)
		values[i] = sm_document_parameter_value(doc, i);
	make_stale(&err);
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE(cleared(&err));
	const int32_t n = sm_model_particle_count(model);
	double x[3 * 16], v[3 * 16];
	ENSURE(n <= 16);
	sm_model_initial_state(model, x, v);
	make_stale(&err);
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, v, &err), SM_OK);
	ENSURE(cleared(&err));
	make_stale(&err);
	char* json = sm_document_to_json(doc, &err);
	ENSURE(json != NULL && cleared(&err));
	free(json);
	make_stale(&err);
	ENSURE_STATUS(sm_document_save(doc, "test_model_file_error_report.json", &err), SM_OK);
	ENSURE(cleared(&err));
	remove("test_model_file_error_report.json");

	const sm_model_def world = sm_default_model_def();
	make_stale(&err);
	sm_model* empty = sm_model_create(&world, &err);
	ENSURE(empty != NULL && cleared(&err));
	sm_model_destroy(empty);
	make_stale(&err);
	sm_simulation* sim = sm_simulation_create(model, NULL, &err);
	ENSURE(sim != NULL && cleared(&err));
	const sm_model* own = sm_simulation_model(sim);  // simulation.h: a reset keeps the pointer
	ENSURE_STATUS(sm_simulation_advance(sim, 0.1), SM_OK);
	ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
	ENSURE(sm_simulation_model(sim) == own);
	sm_simulation_destroy(sim);
	make_stale(&err);
	ENSURE_STATUS(sm_statics_solve(model, NULL, x, NULL, NULL, &err), SM_OK);
	ENSURE(cleared(&err));
	sm_modes modes;
	make_stale(&err);
	ENSURE_STATUS(sm_modes_compute(model, NULL, &modes, &err), SM_OK);
	ENSURE(cleared(&err));
	sm_modes_release(&modes);
	sm_model_destroy(model);
	sm_document_destroy(doc);

	ENSURE(strcmp(sm_method_name((sm_method)9), "unknown") == 0);
	ENSURE(strcmp(sm_jacobian_variant_name((sm_jacobian_variant)7), "unknown") == 0);
	ENSURE(strcmp(sm_linear_solver_name(SM_SOLVER_COUNT), "unknown") == 0);
	ENSURE(strcmp(sm_method_name(SM_METHOD_ADAMS), "adams") == 0);
	ENSURE(strcmp(sm_jacobian_variant_name(SM_JACOBIAN_DEFINITE), "definite") == 0);
	return 0;
}

// The canonical form reads back to the same document (docs/model-format.md, "Canonical form and
// saving"): names and a description holding quotes, backslashes and non-ASCII text; a velocity
// along z alone; simulation settings that need 17 significant digits; and every parameter
// reference kept, also those of a velocity that is zero (w), of gravity and of mass damping, so
// that new values act on the saved document as on the original. After
// sm_document_set_initial_state, a velocity the file took from a parameter is saved as the new
// number, not as the parameter again.
static int test_canonical_form_reads_back(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"s\", \"description\": \"\\\"q\\\" \\\\ caf\xc3\xa9\\t.\","
	    " \"parameters\": {\"v\": 0.5, \"w\": 0, \"g\": -9.81, \"alpha\": 0.1},"
	    " \"gravity\": [0, 0, \"g\"], \"mass_damping\": \"alpha\","
	    " \"particles\": [{\"name\": \"a\\\"b\", \"position\": [0, 0, 0], \"velocity\": [0, 0, 3]},"
	    "  {\"name\": \"c\\\\d\", \"position\": [1, 0, 0], \"velocity\": [\"v\", 0, 0]},"
	    "  {\"name\": \"e\", \"position\": [2, 0, 0], \"velocity\": [0, \"w\", 0]}],"
	    " \"springs\": [{\"a\": \"a\\\"b\", \"b\": \"c\\\\d\", \"stiffness\": 2}],"
	    " \"ports\": [{\"name\": \"p\", \"particle\": \"c\\\\d\", \"kind\": \"probe\"}],"
	    " \"simulation\": {\"stop_time\": 1.2345678901234567, \"rtol\": 1.0000000000000002e-7}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(strcmp(sm_document_description(again), "\"q\" \\ caf\xc3\xa9\t.") == 0);
	ENSURE(strcmp(sm_document_particle_name(again, 0), "a\"b") == 0);
	ENSURE(strcmp(sm_document_particle_name(again, 1), "c\\d") == 0);
	const sm_document_settings settings = sm_document_get_settings(again);
	ENSURE(settings.stop_time == 1.2345678901234567 &&
	       settings.solver.relative_tolerance == 1.0000000000000002e-7);
	const double values[4] = {0.75, 2.0, -1.5, 0.3};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameters(again, values, &err), SM_OK);
	ENSURE(same_document(doc, again) == 0);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	double v[9];
	sm_model_initial_state(m, NULL, v);
	ENSURE(v[2] == 3.0 && v[3] == 0.75 && v[7] == 2.0);
	const sm_model_def def = sm_model_get_def(m);
	ENSURE(def.gravity[2] == -1.5 && def.mass_damping == 0.3);
	sm_model_destroy(m);
	sm_document_destroy(again);

	// A new initial state: c\d moves at 0.25 m/s along x; the saved file starts so, and its
	// parameter v no longer sets that velocity.
	const double x[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0}, moved[9] = {0, 0, 3, 0.25, 0, 0, 0, 2, 0};
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, moved, &err), SM_OK);
	again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(sm_document_parameter_index(again, "v") == -1);  // it would feed nothing
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_model_initial_state(m, NULL, v);
	ENSURE(memcmp(v, moved, sizeof v) == 0);
	sm_model_destroy(m);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// The canonical form is JSON whatever LC_NUMERIC the program chose: under a locale with a decimal
// comma (de_DE), a gravity of 9.81 m/s^2 and a mass of 0.5 kg are still written with a point,
// and the text loads. Where no such locale is installed there is nothing to check.
static int test_canonical_form_ignores_the_locale(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid("{\"springmass\": 1, \"name\": \"x\", \"gravity\": [0, 0, -9.81],"
	                               " \"particles\": [{\"position\": [0, 0, 0], \"mass\": 0.5}]}",
	                               &err);
	ENSURE(doc != NULL);
	if (setlocale(LC_NUMERIC, "de_DE.UTF-8") == NULL) {
		printf("  no de_DE.UTF-8 locale: skipped\n");
		sm_document_destroy(doc);
		return 0;
	}
	char* text = sm_document_to_json(doc, &err);
	setlocale(LC_NUMERIC, "C");
	ENSURE(text != NULL);
	ENSURE(strstr(text, "\"gravity\": [0, 0, -9.81]") != NULL && strstr(text, "\"mass\": 0.5") != NULL);
	sm_document* again = sm_document_parse(text, strlen(text), "saved.json", &err);
	free(text);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// Messages write their numbers with a point whatever LC_NUMERIC the program chose: under a
// decimal comma a model file's refusal said "-0,5 must be > 0", a list "n = 0,5, m = 2" is
// ambiguous, and a value copied from a message into a model file or a command is refused. The
// model file's, the model's and the simulation's messages, and sm_format_number. The program's own
// text keeps its decimal comma after each: the C locale is the thread's for the call only. Where
// no such locale is installed there is nothing to check.
static int test_messages_ignore_the_locale(void)
{
	if (setlocale(LC_NUMERIC, "de_DE.UTF-8") == NULL) {
		printf("  no de_DE.UTF-8 locale: skipped\n");
		return 0;
	}
	char text[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(-0.5, text);
	const bool number_ok = strcmp(text, "-0.5") == 0;
	char after_number[16];
	snprintf(after_number, sizeof after_number, "%g", 0.5);
	sm_error file_err = {SM_OK, ""};
	const char* bad_mass =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mass\": -0.5}]}";
	sm_document* doc = sm_document_parse(bad_mass, strlen(bad_mass), "bad.json", &file_err);
	sm_error model_err = {SM_OK, ""};
	sm_model* model = sm_model_create(&(sm_model_def){.gravity = {0, 0, -9.81}}, &model_err);
	const sm_particle_def negative = {.mass = -0.5, .position = {0, 0, 0}};
	const bool refused = model != NULL && sm_model_add_particle(model, &negative, NULL) != SM_OK;
	const char* model_message = model != NULL ? sm_model_last_error(model) : "";
	char model_text[SM_ERROR_MESSAGE_CAPACITY];
	snprintf(model_text, sizeof model_text, "%s", model_message);
	sm_simulation_def def = sm_default_simulation_def();
	def.relative_tolerance = 1.5e-20;
	sm_error sim_err = {SM_OK, ""};
	sm_simulation* sim = model != NULL ? sm_simulation_create(model, &def, &sim_err) : NULL;
	char after_messages[16];
	snprintf(after_messages, sizeof after_messages, "%g", 0.5);
	setlocale(LC_NUMERIC, "C");
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	ENSURE(number_ok);
	ENSURE(strcmp(after_number, "0,5") == 0 && strcmp(after_messages, "0,5") == 0);
	ENSURE(doc == NULL && strstr(file_err.message, "-0.5 must be > 0") != NULL);
	ENSURE(refused && strcmp(model_text, "particle 0: mass = -0.5 must be > 0") == 0);
	ENSURE(sim == NULL && strstr(sim_err.message, "1.5e-20") != NULL);
	return 0;
}

// What each parameter feeds, for the places test_parameter_uses leaves out, one parameter per
// place (docs/model-format.md, "Parameters"): a particle's velocity, a sheet's origin, edges and
// mass, a block's size, nw and mass, a rope's mass per length, a mesh's density, a spring's break
// strain and section, the simulation's stop time and output interval, the lower corner of a box
// in "fixed" and the mass damping.
static int test_parameter_uses_of_every_place(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"u\", \"parameters\": {\"vel\": 0.5, \"org\": 0, \"eu\": 1, \"ev\": 1,"
	    " \"sm\": 2, \"sz\": 1, \"nw\": 2, \"bm\": 3, \"mpl\": 0.5, \"rho\": 0.2, \"brk\": 0.1, \"sec\": 0.25,"
	    " \"stop\": 2, \"out\": 0.1, \"lo\": -1, \"alpha\": 0.1},"
	    " \"mass_damping\": \"alpha\","
	    " \"particles\": [{\"name\": \"p\", \"position\": [0, 0, 9], \"velocity\": [0, \"vel\", 0]},"
	    "  {\"name\": \"q\", \"position\": [1, 0, 9]}],"
	    " \"springs\": [{\"a\": \"p\", \"b\": \"q\", \"stiffness\": 1, \"break_strain\": \"brk\"},"
	    "  {\"a\": \"p\", \"b\": \"q\", \"section_stiffness\": 1, \"section\": \"sec\"}],"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"origin\": [\"org\", 0, 0], \"edge_u\": [\"eu\", 0, 0],"
	    "   \"edge_v\": [0, \"ev\", 0], \"nu\": 2, \"nv\": 2, \"mass\": \"sm\"},"
	    "  {\"type\": \"block\", \"name\": \"b\", \"origin\": [0, 3, 0], \"size\": [1, \"sz\", 1], \"nu\": 2, \"nv\": 2,"
	    "   \"nw\": \"nw\", \"mass\": \"bm\"},"
	    "  {\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 6, 0], \"end\": [1, 6, 0], \"segments\": 2,"
	    "   \"mass_per_length\": \"mpl\"},"
	    "  {\"type\": \"mesh\", \"name\": \"t\", \"density\": \"rho\", \"vertices\": [[0, 8, 0], [1, 8, 0], [0, 9, 0]],"
	    "   \"triangles\": [[0, 1, 2]]}],"
	    " \"fixed\": [{\"min\": [\"lo\", 7.9, -1], \"max\": [2, 9.1, 1]}],"
	    " \"simulation\": {\"stop_time\": \"stop\", \"output_interval\": \"out\"}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	const struct {
		const char* name;
		uint32_t uses;
	} expected[] = {
	    {"vel", SM_PARAMETER_INITIAL_STATE}, {"org", SM_PARAMETER_INITIAL_STATE},
	    {"eu", SM_PARAMETER_INITIAL_STATE},  {"ev", SM_PARAMETER_INITIAL_STATE},
	    {"sm", SM_PARAMETER_CONSTANTS},      {"sz", SM_PARAMETER_INITIAL_STATE},
	    {"nw", SM_PARAMETER_COUNTS},         {"bm", SM_PARAMETER_CONSTANTS},
	    {"mpl", SM_PARAMETER_CONSTANTS},     {"rho", SM_PARAMETER_CONSTANTS},
	    {"brk", SM_PARAMETER_CONSTANTS},     {"sec", SM_PARAMETER_CONSTANTS},
	    {"stop", SM_PARAMETER_SETTINGS},     {"out", SM_PARAMETER_SETTINGS},
	    {"lo", SM_PARAMETER_MOTION},         {"alpha", SM_PARAMETER_CONSTANTS},
	};
	int wrong = 0;
	for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++) {
		const int32_t k = sm_document_parameter_index(doc, expected[e].name);
		ENSURE(k >= 0);
		if (sm_document_parameter_uses(doc, k) != expected[e].uses) {
			printf("  parameter %s: uses %u, expected %u\n", expected[e].name,
			       (unsigned)sm_document_parameter_uses(doc, k), (unsigned)expected[e].uses);
			wrong++;
		}
	}
	sm_document_destroy(doc);
	return wrong > 0;
}

// Rules at their edges that test_rules_at_their_edges leaves out, each refused with the path of
// the element and the rule: a block's nw of 1 (each count >= 2), a break strain of 0 (> 0), a
// rope's mass per length of 0 (> 0), a number in quotes starting with 0, a spring from a particle
// to itself given by indices, a particle name given twice, a mesh vertex of two numbers (the path
// names that vertex), a block whose particle count overflows 64 bits (2^21 x 2^21 x 2^22 =
// 2^64) refused by its first two counts, a format version of 0 (below the 1 it must be), a mass
// just below DBL_MIN and a largest step of 1 / DBL_MAX itself (a limit is above it). The limits
// that are "at least" take their own value: a mass of DBL_MIN and an rtol of the machine epsilon.
static int test_more_rules_at_their_edges(void)
{
	static const refusal cases[] = {
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"b\", \"size\": [1, 1, 1],"
		 " \"nu\": 2, \"nv\": 2, \"nw\": 1}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0].nw: 1 must be a whole number from 2 to 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\","
		 " \"nu\": 2, \"nv\": 1}]}",
		 SM_ERROR_SCHEMA, "test.json: structures[0].nv: 1 must be a whole number from 2 to 4194304"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\","
		 " \"nu\": 2, \"nv\": 2, \"mass\": 0}]}",
		 SM_ERROR_NEGATIVE, "test.json: structures[0].mass: 0 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"m\": true}, \"particles\": [{\"position\":"
		 " [0, 0, 0]}]}",
		 SM_ERROR_SCHEMA, "test.json: parameters.m: a parameter's value must be a number, not a boolean"},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": 1, \"break_strain\": 0}]}",
		 SM_ERROR_NEGATIVE, "test.json: springs[0].break_strain: 0 must be > 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
		 " \"end\": [1, 0, 0], \"segments\": 2, \"mass_per_length\": 0}]}",
		 SM_ERROR_NEGATIVE, "test.json: structures[0].mass_per_length: 0 must be > 0"},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"0.5\"}]}", SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"0.5\" (a number is written without quotes)"},
	    // Signs before the number and its exponent make a number too; an exponent without digits does not.
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"+1e+3\"}]}", SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"+1e+3\" (a number is written without quotes)"},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 0, \"b\": 1, \"stiffness\": \"1e\"}]}", SM_ERROR_NOT_FOUND,
		 "test.json: springs[0].stiffness: no parameter named \"1e\""},
	    {TWO_PARTICLES ", \"springs\": [{\"a\": 1, \"b\": 1.0, \"stiffness\": 1}]}", SM_ERROR_SELF_SPRING,
		 "test.json: springs[0]: connects particle 1 to itself (a and b are the same particle)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]},"
		 " {\"name\": \"b\", \"position\": [1, 0, 0]}, {\"name\": \"a\", \"position\": [2, 0, 0]}]}",
		 SM_ERROR_SCHEMA, "test.json: particles[2].name: particle name \"a\" is already used by particle 0"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2]]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].vertices[1]: must be an array of 3 numbers [x, y, z], not an array of another "
		 "length"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], 5], \"triangles\": [[0, 1, 2]]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].vertices[2]: must be an array of 3 numbers [x, y, z], not a number"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"mesh\", \"name\": \"m\","
		 " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"triangles\": [[0, 1, 2, 0]]}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0].triangles[0]: must be an array of 3 vertex indices, not of 4"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"block\", \"name\": \"b\", \"size\": [1, 1, 1],"
		 " \"nu\": 2097152, \"nv\": 2097152, \"nw\": 4194304}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: structures[0]: 2097152 x 2097152 x 4194304 particles exceed the limit of 4194304"},
	    // "c[]" is of the form S[...], though no reference has empty brackets.
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"c[]\", \"position\": [5, 5, 5]}],"
		 " \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 2, \"nv\": 2}]}",
		 SM_ERROR_SCHEMA,
		 "test.json: particles[0].name: name \"c[]\" reads as a reference to a particle of structure \"c\": "
		 "give the particle another name"},
	    {"{\"springmass\": 0, \"name\": \"x\"}", SM_ERROR_SCHEMA,
		 "test.json: springmass: format version must be 1 (this build reads version 1)"},
	    {"{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mass\": 2.225073858507201e-308}]}",
		 SM_ERROR_NONPOSITIVE_MASS,
		 "test.json: particles[0].mass: 2.225073858507201e-308 must be at least 2.2250738585072014e-308, the "
		 "smallest normal double (1 / mass would overflow)"},
	    {TWO_PARTICLES ", \"simulation\": {\"max_step\": 5.562684646268003e-309}}", SM_ERROR_SCHEMA,
		 "test.json: simulation.max_step: 5.562684646268003e-309 must be 0 (no limit) or above "
		 "5.562684646268003e-309 s, 1 / DBL_MAX: CVODE takes its inverse"},
	};
	ENSURE(count_wrong_refusals(cases, sizeof cases / sizeof cases[0]) == 0);
	// Only a name of the form S[...] reads as a reference to structure S: "c[" and "c[1" do not.
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse_valid("{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"c[\", \"position\":"
		            " [5, 5, 5]}, {\"name\": \"c[1\", \"position\": [6, 5, 5]}], \"structures\": [{\"type\":"
		            " \"sheet\", \"name\": \"c\", \"nu\": 2, \"nv\": 2}]}",
		            &err);
	ENSURE(doc != NULL);
	ENSURE(sm_document_particle_index(doc, "c[") == 0 && sm_document_particle_index(doc, "c[1") == 1);
	sm_document_destroy(doc);
	doc = parse_valid(
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0],"
	    " \"mass\": 2.2250738585072014e-308}], \"simulation\": {\"rtol\": 2.220446049250313e-16}}",
	    &err);
	ENSURE(doc != NULL);
	ENSURE(sm_document_get_settings(doc).solver.relative_tolerance == 2.220446049250313e-16);
	sm_document_destroy(doc);
	return 0;
}

// Saving keeps what test_canonical_form_keeps_what_the_file_says leaves out: a fixed particle
// whose mass is a parameter stays fixed; a spring's rest length from a parameter stays that
// parameter, so that a new value acts on the saved document as on the original; a motion port on
// a particle other than the first stays on its particle; a particle's mass from a parameter is
// still that parameter after sm_document_set_initial_state (only positions and velocities are
// replaced); and a position, velocity or gravity component of -0 is written -0.0 (the reader
// takes "-0" for the integer 0), so that it reloads as -0, bit for bit, and the saved text is a
// fixed point, also where it is a velocity's only nonzero bit (b's (0, 0, -0), which a velocity
// of zeros, left out, would lose).
static int test_canonical_form_keeps_parameters_and_ports(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"k\", \"parameters\": {\"m\": 2, \"l\": 0.5},"
	    " \"gravity\": [0, -0.0, -9.81],"
	    " \"particles\": [{\"name\": \"a\", \"position\": [-0.0, 0, 0], \"velocity\": [0, -0.0, 1]},"
	    "  {\"name\": \"h\", \"position\": [1, 0, 0], \"mass\": \"m\", \"fixed\": true},"
	    "  {\"name\": \"b\", \"position\": [2, 0, 0], \"velocity\": [0, 0, -0.0]}],"
	    " \"springs\": [{\"a\": \"h\", \"b\": \"b\", \"rest_length\": \"l\", \"stiffness\": 3}],"
	    " \"ports\": [{\"name\": \"base\", \"particle\": \"h\", \"kind\": \"motion\"}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(sm_document_port(again, 0).particle == 1 && sm_document_port(again, 0).kind == SM_PORT_MOTION);
	const double values[2] = {3.0, 0.75};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameters(again, values, &err), SM_OK);
	ENSURE(same_document(doc, again) == 0);
	sm_document_destroy(again);
	char* first = sm_document_to_json(doc, &err);
	ENSURE(first != NULL);
	again = sm_document_parse(first, strlen(first), "saved.json", &err);
	ENSURE(again != NULL);
	char* second = sm_document_to_json(again, &err);
	ENSURE(second != NULL);
	const bool fixed_point = strcmp(first, second) == 0;
	free(first);
	free(second);
	sm_document_destroy(again);
	ENSURE(fixed_point);
	// A new initial state: the mass parameter still feeds the saved particle's mass.
	const double x[9] = {0, 0, 0, 1, 0, 0, 2.5, 0, 0};
	ENSURE_STATUS(sm_document_set_initial_state(doc, x, NULL, &err), SM_OK);
	again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(sm_document_parameter_index(again, "m") >= 0);
	ENSURE_STATUS(sm_document_set_parameter(again, sm_document_parameter_index(again, "m"), 5.0, &err),
	              SM_OK);
	sm_model* m = NULL;
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_particle_def h;
	sm_model_get_particle(m, 1, &h);
	ENSURE(h.mass == 5.0 && h.motion == SM_PARTICLE_FIXED);
	sm_model_destroy(m);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	// A name holding a backslash and a quote is written escaped, and a velocity whose only
	// parameter is its last component, at 0, keeps that parameter: setting it moves the particle.
	doc = parse_valid("{\"springmass\": 1, \"name\": \"k\", \"parameters\": {\"w\": 0}, \"particles\":"
	                  " [{\"name\": \"a\\\\b\\\"c\", \"position\": [0, 0, 0], \"velocity\": [0, 0, \"w\"]}]}",
	                  &err);
	ENSURE(doc != NULL);
	again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(sm_document_particle_index(again, "a\\b\"c") == 0);
	ENSURE(sm_document_parameter_index(again, "w") == 0);
	ENSURE_STATUS(sm_document_set_parameter(again, 0, 2.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(again, &m, NULL), SM_OK);
	sm_particle_def a;
	sm_model_get_particle(m, 0, &a);
	ENSURE(a.velocity[0] == 0.0 && a.velocity[1] == 0.0 && a.velocity[2] == 2.0);
	sm_model_destroy(m);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// Setting a parameter is giving the file its value, down to the sign of a zero: -0 and 0 compare
// equal, but a file that gives "vx": -0.0 starts the particle with a velocity of -0, which the
// saved file and `springmass run`'s CSV write as "-0". So a parameter set from 0 to -0 (or back)
// takes the new value and builds the model the edited file builds, bit for bit, one at a time
// and all at once.
static int test_parameters_keep_the_sign_of_a_zero(void)
{
	const char* text = "{\"springmass\": 1, \"name\": \"z\", \"parameters\": {\"vx\": 0, \"x\": -0.0},"
	                   " \"particles\": [{\"position\": [\"x\", 1, 2], \"velocity\": [\"vx\", 0, 0]}]}";
	const char* edited = "{\"springmass\": 1, \"name\": \"z\", \"parameters\": {\"vx\": -0.0, \"x\": 0},"
	                     " \"particles\": [{\"position\": [\"x\", 1, 2], \"velocity\": [\"vx\", 0, 0]}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	sm_document* want = parse_valid(edited, &err);
	ENSURE(doc != NULL && want != NULL);
	ENSURE_STATUS(sm_document_set_parameter(doc, 0, -0.0, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameter(doc, 1, 0.0, &err), SM_OK);
	ENSURE(signbit(sm_document_parameter_value(doc, 0)) && !signbit(sm_document_parameter_value(doc, 1)));
	sm_model *a = NULL, *b = NULL;
	ENSURE_STATUS(sm_document_build(doc, &a, NULL), SM_OK);
	ENSURE_STATUS(sm_document_build(want, &b, NULL), SM_OK);
	sm_particle_def pa, pb;
	sm_model_get_particle(a, 0, &pa);
	sm_model_get_particle(b, 0, &pb);
	ENSURE(signbit(pa.velocity[0]) && !signbit(pa.position[0]));
	ENSURE(memcmp(pa.position, pb.position, sizeof pa.position) == 0);
	ENSURE(memcmp(pa.velocity, pb.velocity, sizeof pa.velocity) == 0);
	sm_model_destroy(a);
	// Back, all at once: the file's own values.
	const double values[2] = {0.0, -0.0};
	ENSURE_STATUS(sm_document_set_parameters(doc, values, &err), SM_OK);
	ENSURE_STATUS(sm_document_build(doc, &a, NULL), SM_OK);
	sm_model_get_particle(a, 0, &pa);
	ENSURE(!signbit(pa.velocity[0]) && signbit(pa.position[0]));
	sm_model_destroy(a);
	sm_model_destroy(b);
	sm_document_destroy(want);
	sm_document_destroy(doc);
	return 0;
}

// The loader's entry with another limit on particles and springs (each), which the fuzz target
// uses (lib/model_file_internal.h); with a limit of 10 the limits are checked at their edges
// without models of millions of elements.
sm_document* sm_document_parse_limited(const char* text, size_t length, const char* source_name,
                                       int64_t max_elements, sm_error* err);

// Exactly the limit of particles or springs loads and one more is refused: 10 explicit particles,
// and a rope of 5 segments with bending springs (6 particles, 5 + 4 = 9 springs) beside one of 6
// segments (7 particles, 6 + 5 = 11 springs).
static int test_limits_at_their_edges(void)
{
	text t = {NULL, 0, 0};
	for (int n = 10; n <= 11; n++) {
		t.length = 0;
		append(&t, "{\"springmass\": 1, \"name\": \"x\", \"particles\": [");
		for (int i = 0; i < n; i++)
			append(&t, "%s{\"position\": [%d, 0, 0]}", i > 0 ? ", " : "", i);
		append(&t, "]}");
		sm_error err = {SM_OK, ""};
		sm_document* doc = sm_document_parse_limited(t.data, t.length, "test.json", 10, &err);
		if (n == 10) {
			ENSURE(doc != NULL);
		} else {
			ENSURE(doc == NULL &&
			       strcmp(err.message, "test.json: particles: 11 particles exceed the limit of 10") == 0);
		}
		sm_document_destroy(doc);
	}
	free(t.data);
	static const char* const rope =
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0],"
	    " \"end\": [1, 0, 0], \"segments\": %d, \"structural\": {\"stiffness\": 1}, \"bending\": {\"stiffness\": 1}}]}";
	char text[400];
	sm_error err = {SM_OK, ""};
	snprintf(text, sizeof text, rope, 5);
	sm_document* doc = sm_document_parse_limited(text, strlen(text), "test.json", 10, &err);
	ENSURE(doc != NULL);
	sm_document_destroy(doc);
	snprintf(text, sizeof text, rope, 6);
	ENSURE(sm_document_parse_limited(text, strlen(text), "test.json", 10, &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0]: the model would have 11 springs, more than the limit of 10") ==
	       0);
	// Past the limit in particles alone, by one: a rope of 10 segments has 11 particles and 10 springs.
	snprintf(
	    text, sizeof text,
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\", \"name\": \"r\","
	    " \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 10, \"structural\": {\"stiffness\": 1}}]}");
	ENSURE(sm_document_parse_limited(text, strlen(text), "test.json", 10, &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0]: the model would have 11 particles, more than the limit of 10") ==
	       0);
	// A sheet's springs are counted as it makes them: 3 x 3 particles with structural and bend
	// groups make 12 + 6 springs, which a limit of 18 takes and one of 17 does not.
	static const char sheet[] =
	    "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"sheet\", \"name\": \"c\", \"nu\": 3,"
	    " \"nv\": 3, \"structural\": {\"stiffness\": 1}, \"bend\": {\"stiffness\": 1}}]}";
	doc = sm_document_parse_limited(sheet, strlen(sheet), "test.json", 18, &err);
	ENSURE(doc != NULL && sm_document_spring_count(doc) == 18);
	sm_document_destroy(doc);
	ENSURE(sm_document_parse_limited(sheet, strlen(sheet), "test.json", 17, &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0]: the model would have 18 springs, more than the limit of 17") ==
	       0);
	// Past the limit in both at once, by one each: 4 particles and a rope of 6 segments with both
	// groups make 11 particles and 11 springs.
	static const char both[] =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 1, 0]}, {\"position\": [0, 2, 0]},"
	    " {\"position\": [0, 3, 0]}, {\"position\": [0, 4, 0]}], \"structures\": [{\"type\": \"rope\", \"name\": \"r\","
	    " \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 6, \"structural\": {\"stiffness\": 1},"
	    " \"bending\": {\"stiffness\": 1}}]}";
	ENSURE(sm_document_parse_limited(both, strlen(both), "test.json", 10, &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: structures[0]: the model would have 11 particles and 11 springs, more "
	              "than the limit of 10 of each") == 0);
	// Explicit springs count after a structure's: a rope of 5 springs leaves room for 5 more, not 6.
	for (int n = 5; n <= 6; n++) {
		t.data = NULL;
		t.length = t.capacity = 0;
		append(&t, "{\"springmass\": 1, \"name\": \"x\", \"structures\": [{\"type\": \"rope\","
		           " \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 5,"
		           " \"structural\": {\"stiffness\": 1}}], \"springs\": [");
		for (int k = 0; k < n; k++)
			append(&t, "%s{\"a\": \"r[0]\", \"b\": \"r[%d]\", \"stiffness\": 1}", k > 0 ? ", " : "",
			       1 + k % 5);
		append(&t, "]}");
		doc = sm_document_parse_limited(t.data, t.length, "test.json", 10, &err);
		if (n == 5) {
			ENSURE(doc != NULL && sm_document_spring_count(doc) == 10);
		} else {
			ENSURE(doc == NULL &&
			       strcmp(err.message, "test.json: springs: 6 more springs exceed the limit of 10") == 0);
		}
		sm_document_destroy(doc);
		free(t.data);
	}
	return 0;
}

// Numbers at the ends of what a double and a JSON integer hold (docs/model-format.md, "Limits"):
// one too small for a double reads as 0 with the sign strtod gives it, the smallest subnormal
// reads as itself, integers reach -2^63 and 2^63 - 1 (2^63 - 1 rounding to the double 2^63) and
// 9.3e18 is a real number; one too large for a double and an integer past either end are syntax
// errors at their line and column. The comparisons are exact: each value is a double's own.
static int test_numbers_at_the_ends_of_a_double(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    parse_valid("{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [1e-400, -1e-400,"
		            " 4.94065645841247e-324], \"velocity\": [9223372036854775807,"
		            " -9223372036854775808, 9.3e18]}]}",
		            &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE(sm_document_build(doc, &model, &err) == SM_OK);
	sm_particle_def pa;
	sm_model_get_particle(model, 0, &pa);
	ENSURE(pa.position[0] == 0.0 && !signbit(pa.position[0]));
	ENSURE(pa.position[1] == 0.0 && signbit(pa.position[1]));
	ENSURE(pa.position[2] == 0x1p-1074);
	ENSURE(pa.velocity[0] == 0x1p63 && pa.velocity[1] == -0x1p63 && pa.velocity[2] == 9.3e18);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	// A mass too small for a double is a mass of 0.
	ENSURE(
	    parse(
	        "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0], \"mass\": 1e-400}]}",
	        &err) == NULL);
	ENSURE(strcmp(err.message, "test.json: particles[0].mass: 0 must be > 0") == 0);
	static const struct {
		const char* number;
		const char* message;
	} refused[] = {
	    {"1e400", "test.json:1:66: real number overflow near '1e400'"},
	    {"-1e400", "test.json:1:66: real number overflow near '-1e400'"},
	    {"9223372036854775808", "test.json:1:66: too big integer near '9223372036854775808'"},
	    {"-9223372036854775809", "test.json:1:66: too big negative integer near '-9223372036854775809'"},
	};
	for (size_t k = 0; k < sizeof refused / sizeof refused[0]; k++) {
		char text[200];
		snprintf(text, sizeof text,
		         "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, %s]}]}",
		         refused[k].number);
		ENSURE(parse(text, &err) == NULL && err.status == SM_ERROR_SYNTAX);
		if (strcmp(err.message, refused[k].message) != 0) {
			printf("  %s\n", err.message);
			return 1;
		}
	}
	return 0;
}

// A spring's explicit "kind" stays in the saved file when its rest length is a parameter, so that
// the parameter feeds the same (constants, not spring kinds) and a new value acts alike: l = 0
// keeps spring 0 a rest-length spring, and z = 0.3 is refused by both documents. Without a kind
// (spring 2), the parameter keeps choosing the law in both.
static int test_saved_springs_keep_their_kind(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"k\", \"gravity\": [0, 0, 0], \"parameters\": {\"l\": 0.5, \"z\": 0, \"w\": 0.7},"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"kind\": \"rest_length\", \"rest_length\": \"l\", \"stiffness\": 10},"
	    "  {\"a\": \"a\", \"b\": \"b\", \"kind\": \"zero_length\", \"rest_length\": \"z\", \"stiffness\": 1},"
	    "  {\"a\": \"a\", \"b\": \"b\", \"rest_length\": \"w\", \"stiffness\": 1}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	for (int32_t k = 0; k < 3; k++)
		ENSURE(sm_document_parameter_uses(again, k) == sm_document_parameter_uses(doc, k));
	ENSURE(sm_document_parameter_uses(doc, 2) == (SM_PARAMETER_CONSTANTS | SM_PARAMETER_SPRING_KINDS));
	const double zero[3] = {0.0, 0.0, 0.0};
	ENSURE_STATUS(sm_document_set_parameters(doc, zero, &err), SM_OK);
	ENSURE_STATUS(sm_document_set_parameters(again, zero, &err), SM_OK);
	ENSURE(same_document(doc, again) == 0);
	ENSURE_STATUS(sm_document_set_parameter(doc, 1, 0.3, &err), SM_ERROR_SCHEMA);
	ENSURE_STATUS(sm_document_set_parameter(again, 1, 0.3, &err), SM_ERROR_SCHEMA);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// A message on a value from a parameter shows the parameter's value also when its name has the
// full 200 bytes: a count (a rope's segments) and a vector (a sheet's zero edge).
static int test_messages_show_values_of_long_parameters(void)
{
	char name[201], text[1024];
	memset(name, 'n', 200);
	name[200] = '\0';
	snprintf(
	    text, sizeof text,
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"%s\": 2.5}, \"structures\": [{\"type\": \"rope\","
	    " \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": \"%s\"}]}",
	    name, name);
	sm_error err = {SM_OK, ""};
	ENSURE(parse(text, &err) == NULL);
	ENSURE(strstr(err.message, " = 2.5 must be a whole number from 1 to 4194304") != NULL);
	snprintf(
	    text, sizeof text,
	    "{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"%s\": 0}, \"structures\": [{\"type\": \"sheet\","
	    " \"name\": \"c\", \"edge_u\": [\"%s\", 0, 0], \"nu\": 2, \"nv\": 2}]}",
	    name, name);
	ENSURE(parse(text, &err) == NULL);
	ENSURE(strstr(err.message, " = 0, 0, 0) m is zero") != NULL);
	return 0;
}

// A spring constant of 0 given per strain or per section keeps its scaling (and its section)
// through a save: the same spring definitions, not absolute zeros (same_document compares every
// field of every spring).
static int test_saved_zero_constants_keep_their_scaling(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"zs\", \"gravity\": [0, 0, 0],"
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"strain_stiffness\": 0, \"damping\": 1},"
	    "  {\"a\": \"a\", \"b\": \"b\", \"section_stiffness\": 0, \"section\": 0.5, \"strain_damping\": 2},"
	    "  {\"a\": \"a\", \"b\": \"b\", \"stiffness\": 3, \"section_damping\": 0, \"section\": 0.25}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// A spring constant of -0 given as a number (an explicit spring's, a structure group's) reloads
// as -0: the loader keeps the sign of the zero in the model, and the canonical form, which leaves
// out a constant of 0, writes this one, so that the saved file builds the same model bit for bit,
// as it does for a position or velocity of -0 (same_model compares constants with ==, which takes
// -0 for 0: the sign is checked here).
static int test_saved_negative_zero_constants_keep_their_sign(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"nz\","
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 1, 0], \"end\": [1, 1, 0], \"segments\": 1,"
	    "  \"structural\": {\"stiffness\": -0.0, \"damping\": 1}}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 2, \"damping\": -0.0},"
	    "  {\"a\": \"a\", \"b\": \"r[0]\", \"stiffness\": -0.0, \"damping\": -0.0}]}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	sm_model *a = NULL, *b = NULL;
	ENSURE_STATUS(sm_document_build(doc, &a, NULL), SM_OK);
	ENSURE_STATUS(sm_document_build(again, &b, NULL), SM_OK);
	// The rope's spring (0), then the file's two: the zeros of the file, signs and all.
	const bool negative[3][2] = {{true, false}, {false, true}, {true, true}};
	ENSURE(sm_model_spring_count(a) == 3);
	for (int32_t s = 0; s < 3; s++) {
		double ka, da, kb, db;
		sm_model_spring_constants(a, s, NULL, &ka, &da);
		sm_model_spring_constants(b, s, NULL, &kb, &db);
		ENSURE(!!signbit(ka) == negative[s][0] && !!signbit(da) == negative[s][1]);
		ENSURE(memcmp(&ka, &kb, sizeof ka) == 0 && memcmp(&da, &db, sizeof da) == 0);
	}
	sm_model_destroy(a);
	sm_model_destroy(b);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// The canonical form lists only the parameters it names, and a choice of the simulation settings
// names none: a parameter that feeds nothing, called as a method, solver, Jacobian or input change
// is ("bdf", "klu", "definite", "keep"), is left out of the saved file, as one of any other name
// is; one that a number of the settings names ("stop_time": "adams") is kept.
static int test_saved_choices_name_no_parameters(void)
{
	const char* text =
	    "{\"springmass\": 1, \"name\": \"ch\","
	    " \"parameters\": {\"bdf\": 1, \"klu\": 2, \"definite\": 3, \"keep\": 4, \"adams\": 2.5, \"other\": 5},"
	    " \"particles\": [{\"position\": [0, 0, 0]}],"
	    " \"simulation\": {\"method\": \"bdf\", \"solver\": \"klu\", \"jacobian\": \"definite\","
	    "  \"input_changes\": \"keep\", \"stop_time\": \"adams\"}}";
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	static const char* const unused[] = {"bdf", "klu", "definite", "keep", "other"};
	for (size_t k = 0; k < sizeof unused / sizeof unused[0]; k++)
		ENSURE(sm_document_parameter_uses(doc, sm_document_parameter_index(doc, unused[k])) == 0);
	sm_document* again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(sm_document_parameter_count(again) == 1);
	ENSURE(strcmp(sm_document_parameter_name(again, 0), "adams") == 0);
	ENSURE(sm_document_parameter_uses(again, 0) == SM_PARAMETER_SETTINGS);
	const sm_document_settings settings = sm_document_get_settings(again);
	ENSURE(settings.stop_time == 2.5 && settings.solver.method == SM_METHOD_BDF &&
	       settings.solver.solver == SM_SOLVER_KLU && settings.solver.jacobian == SM_JACOBIAN_DEFINITE &&
	       !settings.solver.restart_on_input_change);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	// The file's first parameter, named by a setting alone, is kept too.
	doc = parse_valid("{\"springmass\": 1, \"name\": \"first\", \"parameters\": {\"T\": 3},"
	                  " \"particles\": [{\"position\": [0, 0, 0]}], \"simulation\": {\"stop_time\": \"T\"}}",
	                  &err);
	ENSURE(doc != NULL);
	again = save_and_load(doc);
	ENSURE(again != NULL);
	ENSURE(sm_document_parameter_index(again, "T") == 0 && sm_document_get_settings(again).stop_time == 3.0);
	sm_document_destroy(again);
	sm_document_destroy(doc);
	return 0;
}

// A saved file keeps the units its parameters had: a structure's per-section constant, written as
// a single spring's (whose section is a width or an area, so the key tells no unit), keeps the
// unit its structure gave it through "parameter_units", for the trampoline's sheet (N/m, N s/m)
// and a block (N/m^2, N s/m^2); parameters the saved text names where the key tells the unit get
// no entry, and saving the saved file gives the same bytes.
static int test_saved_structures_keep_parameter_units(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = load_bundled("trampoline", &err);
	ENSURE(doc != NULL);
	char* text = sm_document_to_json(doc, &err);
	ENSURE(text != NULL);
	ENSURE(strstr(text, "\n  \"parameters\": {\"Y\": 40000, \"eta\": 20},\n"
	                    "  \"parameter_units\": {\"Y\": \"N/m\", \"eta\": \"N.s/m\"},\n") != NULL);
	sm_document* again = sm_document_parse(text, strlen(text), "saved.json", &err);
	ENSURE(again != NULL);
	ENSURE(same_document(doc, again) == 0);
	ENSURE(strcmp(sm_document_parameter_unit(again, sm_document_parameter_index(again, "Y")), "N/m") == 0);
	ENSURE(strcmp(sm_document_parameter_unit(again, sm_document_parameter_index(again, "eta")), "N.s/m") ==
	       0);
	char* text_again = sm_document_to_json(again, &err);
	ENSURE(text_again != NULL && strcmp(text, text_again) == 0);
	free(text_again);
	free(text);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	const char* block =
	    "{\"springmass\": 1, \"name\": \"b\", \"parameters\": {\"Y\": 1000, \"D\": 2, \"k\": 50, \"g\": -9.81, \"tol\": 1e-6},"
	    " \"gravity\": [0, 0, \"g\"],"
	    " \"structures\": [{\"type\": \"block\", \"name\": \"b\", \"size\": [1, 1, 1], \"nu\": 2, \"nv\": 2, \"nw\": 2,"
	    "   \"edge\": {\"section_stiffness\": \"Y\", \"section_damping\": \"D\"}, \"body_diagonal\": {\"stiffness\": \"k\"}}],"
	    " \"simulation\": {\"rtol\": \"tol\"}}";
	doc = parse_valid(block, &err);
	ENSURE(doc != NULL);
	text = sm_document_to_json(doc, &err);
	ENSURE(text != NULL);
	ENSURE(strstr(text, "\"parameter_units\": {\"Y\": \"N/m2\", \"D\": \"N.s/m2\"},\n") != NULL);
	again = sm_document_parse(text, strlen(text), "saved.json", &err);
	ENSURE(again != NULL);
	static const char* const names[] = {"Y", "D", "k", "g", "tol"};
	for (size_t k = 0; k < sizeof names / sizeof names[0]; k++)
		ENSURE(strcmp(sm_document_parameter_unit(doc, sm_document_parameter_index(doc, names[k])),
		              sm_document_parameter_unit(again, sm_document_parameter_index(again, names[k]))) == 0);
	text_again = sm_document_to_json(again, &err);
	ENSURE(text_again != NULL && strcmp(text, text_again) == 0);
	free(text_again);
	free(text);
	sm_document_destroy(again);
	sm_document_destroy(doc);

	// Without per-section constants, and with structures whose constants keep their unit in a
	// single spring, the saved file has no "parameter_units", as before.
	static const char* const plain[] = {"oscillator", "two_mass_chain", "hanging_rope", "cloth",
	                                    "jelly_block"};
	for (size_t k = 0; k < sizeof plain / sizeof plain[0]; k++) {
		doc = load_bundled(plain[k], &err);
		ENSURE(doc != NULL);
		text = sm_document_to_json(doc, &err);
		ENSURE(text != NULL);
		ENSURE(strstr(text, "parameter_units") == NULL);
		free(text);
		sm_document_destroy(doc);
	}
	return 0;
}

// "parameter_units" gives a unit to a parameter whose keys do not tell one (a single spring's
// per-section constant and section, atol, or nothing), which the document then reports and its
// saved and self-contained texts keep; a unit that disagrees with a key naming the parameter, a
// count or an index, a unit no value has, or a parameter not declared are refused.
static int test_declared_parameter_units(void)
{
	const char* head =
	    "{\"springmass\": 1, \"name\": \"d\", \"parameters\": {\"Y\": 100, \"w\": 0.1, \"k\": 5, \"n\": 2,"
	    " \"atol\": 1e-8, \"spare\": 3},";
	const char* body =
	    " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 1, 0], \"end\": [1, 1, 0], \"segments\": \"n\"}],"
	    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"section_stiffness\": \"Y\", \"section\": \"w\"},"
	    "             {\"a\": \"a\", \"b\": \"r[n - 1]\", \"stiffness\": \"k\"}],"
	    " \"simulation\": {\"atol\": \"atol\"}}";
	char text[2048];
	snprintf(text, sizeof text,
	         "%s \"parameter_units\": {\"Y\": \"N/m2\", \"w\": \"m2\", \"atol\": \"m\","
	         " \"spare\": \"kg\", \"k\": \"N/m\"},%s",
	         head, body);
	// "m2" is no unit a key gives.
	sm_error err = {SM_OK, ""};
	ENSURE(parse(text, &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: parameter_units.w: \"m2\" is no unit a value can have: one of \"kg\", "
	              "\"N\", \"m\", \"m/s\", \"1\", \"N/m\", \"N.s/m\", \"N.s\", \"kg/m\", \"kg/m2\", "
	              "\"m/s2\", \"1/s\", \"s\", \"N/m2\", \"N.s/m2\"") == 0);
	ENSURE(err.status == SM_ERROR_SCHEMA);
	snprintf(text, sizeof text,
	         "%s \"parameter_units\": {\"Y\": \"N/m2\", \"w\": \"m\", \"atol\": \"m\","
	         " \"spare\": \"kg\", \"k\": \"N/m\"},%s",
	         head, body);
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	static const struct {
		const char* name;
		const char* unit;
	} expected[] = {{"Y", "N/m2"}, {"w", "m"}, {"k", "N/m"}, {"n", ""}, {"atol", "m"}, {"spare", "kg"}};
	for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++)
		ENSURE(strcmp(sm_document_parameter_unit(doc, sm_document_parameter_index(doc, expected[e].name)),
		              expected[e].unit) == 0);
	// The units stay through a change of the counts.
	ENSURE_STATUS(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), 3.0, &err), SM_OK);
	ENSURE(strcmp(sm_document_parameter_unit(doc, sm_document_parameter_index(doc, "Y")), "N/m2") == 0);
	// Saved: the parameters named where no key tells their unit keep it ("k" needs no entry; "spare"
	// feeds nothing and is left out with its unit); self-contained: the file as it was.
	char* saved = sm_document_to_json(doc, &err);
	ENSURE(saved != NULL);
	ENSURE(strstr(saved, "\"parameter_units\": {\"Y\": \"N/m2\", \"w\": \"m\", \"atol\": \"m\"},\n") != NULL);
	char* whole = sm_document_to_self_contained_json(doc, &err);
	ENSURE(whole != NULL);
	const char* const texts[2] = {saved, whole};
	for (int t = 0; t < 2; t++) {
		sm_document* again = sm_document_parse(texts[t], strlen(texts[t]), "again.json", &err);
		ENSURE(again != NULL);
		for (size_t e = 0; e < sizeof expected / sizeof expected[0]; e++) {
			const int32_t k = sm_document_parameter_index(again, expected[e].name);
			ENSURE(k >= 0 || t == 0);
			ENSURE(k < 0 || strcmp(sm_document_parameter_unit(again, k), expected[e].unit) == 0);
		}
		sm_document_destroy(again);
	}
	free(whole);
	free(saved);
	sm_document_destroy(doc);

	const struct {
		const char* units;
		sm_status status;
		const char* message;
	} refused[] = {
	    {"{\"k\": \"N/m2\"}", SM_ERROR_SCHEMA,
		 "test.json: springs[1].stiffness: parameter \"k\" stands for a value in N/m here, but "
		 "\"parameter_units\" gives it N/m2"},
	    {"{\"n\": \"1\"}", SM_ERROR_SCHEMA,
		 "test.json: structures[0].segments: parameter \"n\" stands for a count or an index here, which has "
		 "no unit, but \"parameter_units\" gives it 1"},
	    {"{\"q\": \"N\"}", SM_ERROR_NOT_FOUND,
		 "test.json: parameter_units.q: no parameter named \"q\" (\"parameter_units\" gives units to the "
		 "\"parameters\")"},
	    {"{\"k\": 3}", SM_ERROR_SCHEMA,
		 "test.json: parameter_units.k: must be the name of a unit, one of \"kg\", \"N\", \"m\", \"m/s\", \"1\", "
		 "\"N/m\", \"N.s/m\", \"N.s\", \"kg/m\", \"kg/m2\", \"m/s2\", \"1/s\", \"s\", \"N/m2\", \"N.s/m2\", not a "
		 "number"},
	    {"[\"k\"]", SM_ERROR_SCHEMA, "test.json: parameter_units: must be an object, not an array"},
	};
	for (size_t r = 0; r < sizeof refused / sizeof refused[0]; r++) {
		snprintf(text, sizeof text, "%s \"parameter_units\": %s,%s", head, refused[r].units, body);
		ENSURE(parse(text, &err) == NULL);
		if (err.status != refused[r].status || strcmp(err.message, refused[r].message) != 0)
			printf("  %s\n  expected %s\n", err.message, refused[r].message);
		ENSURE(err.status == refused[r].status && strcmp(err.message, refused[r].message) == 0);
	}
	// An index of a structure reference has no unit either; nor is a parameter of a file without
	// "parameters" there to take one.
	ENSURE(
	    parse(
	        "{\"springmass\": 1, \"name\": \"i\", \"parameters\": {\"i\": 1}, \"parameter_units\": {\"i\": \"m\"},"
	        " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": 2}],"
	        " \"ports\": [{\"name\": \"p\", \"particle\": \"r[i]\", \"kind\": \"probe\"}]}",
	        &err) == NULL);
	ENSURE(strcmp(err.message,
	              "test.json: parameter_units.i: parameter \"i\" stands for an index of a structure "
	              "reference, which has no unit, not m") == 0);
	ENSURE(parse("{\"springmass\": 1, \"name\": \"i\", \"parameter_units\": {\"i\": \"m\"},"
	             " \"particles\": [{\"position\": [0, 0, 0]}]}",
	             &err) == NULL);
	ENSURE(err.status == SM_ERROR_NOT_FOUND &&
	       strstr(err.message, "parameter_units.i: no parameter named") != NULL);
	return 0;
}

// A key that is not listed is an error wherever it stands (docs: "The format is strict"), named
// with the keys allowed there: in a structure, a fixed box, a port and the simulation and FMU
// settings too, beside keys that are all valid.
static int test_unknown_keys_are_refused_everywhere(void)
{
	static const char* const format =
	    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"position\": [0, 0, 0]}],"
	    " \"structures\": [{\"type\": \"rope\", \"name\": \"r\", \"start\": [0, 1, 0], \"end\": [1, 1, 0],"
	    " \"segments\": 2%s}], \"fixed\": [{\"min\": [0, 0, 0], \"max\": [0, 0, 0]%s}],"
	    " \"ports\": [{\"name\": \"tip\", \"particle\": \"r[2]\", \"kind\": \"probe\"%s}],"
	    " \"simulation\": {\"stop_time\": 2%s}, \"fmu\": {\"particle_variables\": false%s}}";
	static const struct {
		int place;
		const char* key;
		const char* message;
	} cases[] = {
	    {0, "bendng",
		 "test.json: structures[0]: unknown key \"bendng\" (allowed here: type, name, start, end, segments, "
		 "mass, mass_per_length, structural, bending, mass_distribution)"},
	    {1, "mx", "test.json: fixed[0]: unknown key \"mx\" (allowed here: min, max)"},
	    {2, "knd", "test.json: ports[0]: unknown key \"knd\" (allowed here: name, particle, kind)"},
	    {3, "stop_tme",
		 "test.json: simulation: unknown key \"stop_tme\" (allowed here: stop_time, output_interval, rtol, "
		 "atol, atol_position, atol_velocity, method, solver, jacobian, max_step, max_steps, input_changes, "
		 "stability_limit_detection)"},
	    {4, "particle_variable",
		 "test.json: fmu: unknown key \"particle_variable\" (allowed here: particle_variables)"},
	};
	const char* none[5] = {"", "", "", "", ""};
	char text[1024];
	snprintf(text, sizeof text, format, none[0], none[1], none[2], none[3], none[4]);
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid(text, &err);
	ENSURE(doc != NULL);
	sm_document_destroy(doc);
	int failures = 0;
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		const char* extra[5] = {"", "", "", "", ""};
		char key[64];
		snprintf(key, sizeof key, ", \"%s\": 1", cases[c].key);
		extra[cases[c].place] = key;
		snprintf(text, sizeof text, format, extra[0], extra[1], extra[2], extra[3], extra[4]);
		failures += !refused_as(text, cases[c].key, SM_ERROR_SCHEMA, cases[c].message);
	}
	ENSURE(failures == 0);
	return 0;
}

// A parameter index out of range names no parameter (docs: model_file.h): no name, a NaN value,
// no uses, and setting it fails with the document unchanged, at -1 as at the parameter count.
static int test_parameter_indices_out_of_range(void)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_valid("{\"springmass\": 1, \"name\": \"x\", \"parameters\": {\"m\": 2,"
	                               " \"k\": 3}, \"particles\": [{\"position\": [0, 0, 0], \"mass\": \"m\"}]}",
	                               &err);
	ENSURE(doc != NULL && sm_document_parameter_count(doc) == 2);
	static const int32_t outside[] = {-1, 2};
	for (size_t k = 0; k < sizeof outside / sizeof outside[0]; k++) {
		const int32_t i = outside[k];
		ENSURE(sm_document_parameter_name(doc, i) == NULL && isnan(sm_document_parameter_value(doc, i)));
		ENSURE(sm_document_parameter_uses(doc, i) == 0);
		ENSURE_STATUS(sm_document_set_parameter(doc, i, 5.0, &err), SM_ERROR_NOT_FOUND);
		char expected[100];
		snprintf(expected, sizeof expected, "test.json: parameter index %d is out of range (2 parameters)",
		         (int)i);
		ENSURE(strcmp(err.message, expected) == 0);
		ENSURE(sm_document_parameter_value(doc, 0) == 2.0 && sm_document_parameter_value(doc, 1) == 3.0);
	}
	sm_document_destroy(doc);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_bundled_models_round_trip);
	RUN_TEST(test_oscillator);
	RUN_TEST(test_parameter_uses);
	RUN_TEST(test_potential_terms);
	RUN_TEST(test_force_terms);
	RUN_TEST(test_parameter_units);
	RUN_TEST(test_loads);
	RUN_TEST(test_parameters_set_together);
	RUN_TEST(test_oscillator_follows_its_closed_form);
	RUN_TEST(test_tearing_cloth_tears);
	RUN_TEST(test_cloth_is_the_benchmark_cloth);
	RUN_TEST(test_bundled_model_facts);
	RUN_TEST(test_parameters);
	RUN_TEST(test_initial_state_and_save_to_file);
	RUN_TEST(test_references);
	RUN_TEST(test_broken_files);
	RUN_TEST(test_fixed_boxes_are_limited);
	RUN_TEST(test_messages_quote_text);
	RUN_TEST(test_messages_name_parameters);
	RUN_TEST(test_names_and_descriptions_refuse_controls_and_line_breaks);
	RUN_TEST(test_hostile_input);
	RUN_TEST(test_long_and_control_character_paths_in_messages);
	RUN_TEST(test_byte_order_mark_and_directories);
	RUN_TEST(test_special_files_and_nul_bytes);
	RUN_TEST(test_whole_real_index);
	RUN_TEST(test_canonical_form_keeps_what_the_file_says);
	RUN_TEST(test_longest_structure_names_round_trip);
	RUN_TEST(test_structure_limit_counts_the_groups_present);
	RUN_TEST(test_large_model_loads);
	RUN_TEST(test_many_particles_beside_many_structures_load);
	RUN_TEST(test_rules_at_their_edges);
	RUN_TEST(test_references_stay_inside_their_structures);
	RUN_TEST(test_mesh_references_take_one_index);
	RUN_TEST(test_names_of_200_bytes);
	RUN_TEST(test_settings_and_their_defaults);
	RUN_TEST(test_groups_with_one_parameter_keep_their_springs);
	RUN_TEST(test_saved_groups_keep_their_parameters);
	RUN_TEST(test_fixed_particles_start_at_rest);
	RUN_TEST(test_initial_state_through_parameter_changes);
	RUN_TEST(test_document_counts);
	RUN_TEST(test_dropping_the_initial_state);
	RUN_TEST(test_dropping_the_initial_state_restores_the_file_velocities);
	RUN_TEST(test_syntax_error_positions);
	RUN_TEST(test_line_breaks_and_controls_at_their_edges);
	RUN_TEST(test_messages_escape_invisible_characters);
	RUN_TEST(test_text_for_terminal);
	RUN_TEST(test_status_texts);
	RUN_TEST(test_error_reports_are_filled_on_success);
	RUN_TEST(test_per_section_constants_in_a_model_file);
	RUN_TEST(test_canonical_form_reads_back);
	RUN_TEST(test_canonical_form_ignores_the_locale);
	RUN_TEST(test_messages_ignore_the_locale);
	RUN_TEST(test_reference_expressions);
	RUN_TEST(test_references_follow_their_parameters);
	RUN_TEST(test_parameter_uses_of_every_place);
	RUN_TEST(test_more_rules_at_their_edges);
	RUN_TEST(test_saved_springs_keep_their_kind);
	RUN_TEST(test_messages_show_values_of_long_parameters);
	RUN_TEST(test_saved_zero_constants_keep_their_scaling);
	RUN_TEST(test_saved_negative_zero_constants_keep_their_sign);
	RUN_TEST(test_saved_choices_name_no_parameters);
	RUN_TEST(test_canonical_form_keeps_parameters_and_ports);
	RUN_TEST(test_parameters_keep_the_sign_of_a_zero);
	RUN_TEST(test_limits_at_their_edges);
	RUN_TEST(test_numbers_at_the_ends_of_a_double);
	RUN_TEST(test_unknown_keys_are_refused_everywhere);
	RUN_TEST(test_saved_structures_keep_parameter_units);
	RUN_TEST(test_declared_parameter_units);
	RUN_TEST(test_parameter_indices_out_of_range);
	RUN_TEST(test_springs_are_numbered_structures_first);
	return TEST_SUMMARY();
}

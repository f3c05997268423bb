// No mutable global state: every kind of work the library does (parsing a model file with every
// structure kind, building models, simulating with every linear solver and with Adams, breaking
// springs, statics, modes, the sparse Jacobian, saving) gives the same bits when several copies,
// and a mix of kinds, run at once in POSIX threads as when it runs alone.
//
// Each kind of work reduces its results to a 64-bit FNV-1a hash of their bytes (positions,
// velocities, solver counters, frequencies and shapes, matrix entries, the saved text, ...),
// computed once alone (twice: a lone run must be repeatable for a difference under threads to
// mean anything), then by several threads released together from a barrier. The threads share
// the inputs the API takes as const (the model text, one document, the models to simulate or
// analyse, one sparse pattern), since concurrent const use is documented as safe.
//
// The reduced solver is built into this test with the multilevel threshold lowered (as for
// simulation_multilevel) so that a 12 x 12 cloth runs the multilevel coarse solve while an
// 11 x 11 one runs the two-level preconditioner with the exact coarse solve; the sizes are in
// lib/linear_solver_reduced.c (two-level from 100 free particles, block Jacobi alone below). The
// chunked loops' threshold is lowered the same way (and their limit on springs between chunks
// raised), so that the 12 x 12 cloth runs in chunks, once on the calling thread and once on a team
// of 2 threads, which must give the same bits.
// Built with -fsanitize=thread, the same test is the race check of the library (CHOLMOD's OpenMP
// loops, whose joins inside the uninstrumented libgomp ThreadSanitizer could not see, run on the
// calling thread: lib/cholmod_factorize.c).
#define _POSIX_C_SOURCE 200809L

#include "springmass/springmass.h"
#include "test_harness.h"
#include "workers.h"

#include <dirent.h>
#include <fenv.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#if !defined(MULTILEVEL_MIN_PARTICLES) || MULTILEVEL_MIN_PARTICLES > 142 || MULTILEVEL_MIN_PARTICLES < 120
#error "build lib/linear_solver_reduced.c into this test with 120 <= MULTILEVEL_MIN_PARTICLES <= 142"
#endif

// Copies of one kind run at once, and threads per kind in the mixed run.
enum { COPIES = 4, MIXED_COPIES = 2 };

// ---------------------------------------------------------------------------------------------
// Hashing results: FNV-1a over the bytes, so "the same hash" means the same bits.
// ---------------------------------------------------------------------------------------------

static void hash_bytes(uint64_t* h, const void* data, size_t size)
{
	const unsigned char* p = data;
	for (size_t i = 0; i < size; i++) {
		*h ^= p[i];
		*h *= 0x100000001b3u;
	}
}

static void hash_doubles(uint64_t* h, const double* x, size_t count)
{
	hash_bytes(h, x, count * sizeof(double));
}

static void hash_int(uint64_t* h, int64_t value)
{
	hash_bytes(h, &value, sizeof value);
}

static void hash_text(uint64_t* h, const char* s)
{
	if (s == NULL)
		hash_int(h, -1);
	else
		hash_bytes(h, s, strlen(s) + 1);
}

// Everything the model holds: particles, springs as given and resolved, enabled flags, gravity
// and mass damping.
static void hash_model(uint64_t* h, const sm_model* model)
{
	const int32_t n = sm_model_particle_count(model);
	const int32_t m = sm_model_spring_count(model);
	hash_int(h, n);
	hash_int(h, m);
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		hash_doubles(h, &p.mass, 1);
		hash_doubles(h, p.position, 3);
		hash_doubles(h, p.velocity, 3);
		hash_int(h, p.motion);
	}
	for (int32_t s = 0; s < m; s++) {
		sm_spring_def d;
		sm_model_get_spring(model, s, &d);
		double resolved[3];
		sm_model_spring_constants(model, s, &resolved[0], &resolved[1], &resolved[2]);
		const int64_t kind[6] = {
		    d.a, d.b, d.kind, d.stiffness_scaling, d.damping_scaling, sm_model_spring_enabled(model, s)};
		const double given[4] = {d.rest_length, d.stiffness, d.damping, d.break_strain};
		hash_bytes(h, kind, sizeof kind);
		hash_doubles(h, given, 4);
		hash_doubles(h, resolved, 3);
	}
	const sm_model_def def = sm_model_get_def(model);
	hash_doubles(h, def.gravity, 3);
	hash_doubles(h, &def.mass_damping, 1);
}

// ---------------------------------------------------------------------------------------------
// Inputs, built once by the main thread and only read by the workers.
// ---------------------------------------------------------------------------------------------

// A model file with every structure kind, explicit particles and springs of both kinds,
// parameters feeding constants and counts, fixed particles by name and by box, ports and
// settings.
static const char model_text[] =
    "{\n"
    "  \"springmass\": 1, \"name\": \"threads\", \"description\": \"every structure kind\",\n"
    "  \"parameters\": { \"E\": 800.0, \"c\": 0.4, \"n\": 5, \"m\": 0.3 },\n"
    "  \"gravity\": [0, 0, -9.81], \"mass_damping\": 0.05,\n"
    "  \"structures\": [\n"
    "    { \"type\": \"rope\", \"name\": \"rope\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": \"n\",\n"
    "      \"mass\": \"m\", \"structural\": { \"strain_stiffness\": \"E\", \"strain_damping\": \"c\" },\n"
    "      \"bending\": { \"strain_stiffness\": 20 } },\n"
    "    { \"type\": \"sheet\", \"name\": \"cloth\", \"origin\": [0, 1, 0], \"edge_u\": [1, 0, 0], \"edge_v\": [0, 0, 1],\n"
    "      \"nu\": 4, \"nv\": 3, \"mass\": 0.5,\n"
    "      \"structural\": { \"strain_stiffness\": \"E\", \"strain_damping\": \"c\", \"break_strain\": 0.3 },\n"
    "      \"shear\": { \"strain_stiffness\": 100 }, \"bend\": { \"strain_stiffness\": 10 } },\n"
    "    { \"type\": \"block\", \"name\": \"jelly\", \"origin\": [2, 0, 0], \"size\": [0.3, 0.3, 0.3],\n"
    "      \"nu\": 3, \"nv\": 2, \"nw\": 2, \"mass\": 1.0,\n"
    "      \"edge\": { \"strain_stiffness\": \"E\" }, \"face_diagonal\": { \"strain_stiffness\": 300 },\n"
    "      \"body_diagonal\": { \"strain_stiffness\": 200, \"strain_damping\": 0.1 } },\n"
    "    { \"type\": \"mesh\", \"name\": \"flag\", \"density\": 0.2,\n"
    "      \"vertices\": [[0, 3, 0], [1, 3, 0], [0, 3, 1], [1, 3, 1], [0.5, 3.2, 1.5]],\n"
    "      \"triangles\": [[0, 1, 3], [0, 3, 2], [2, 3, 4]],\n"
    "      \"edge\": { \"strain_stiffness\": 500, \"strain_damping\": 0.5 }, \"bend\": { \"strain_stiffness\": 2 } }\n"
    "  ],\n"
    "  \"particles\": [\n"
    "    { \"name\": \"anchor\", \"position\": [-1, 0, 1], \"fixed\": true },\n"
    "    { \"name\": \"bob\", \"position\": [-1, 0, 0.2], \"velocity\": [0, 0.5, 0], \"mass\": \"m\" }\n"
    "  ],\n"
    "  \"springs\": [\n"
    "    { \"a\": \"anchor\", \"b\": \"bob\", \"stiffness\": 40, \"damping\": 0.4, \"rest_length\": 0.5 },\n"
    "    { \"a\": \"bob\", \"b\": \"rope[0]\", \"kind\": \"zero_length\", \"stiffness\": 5 },\n"
    "    { \"a\": \"rope[5]\", \"b\": \"jelly[0,0,0]\", \"strain_stiffness\": \"E\", \"break_strain\": 0.5 }\n"
    "  ],\n"
    "  \"fixed\": [\"cloth[2,0]\", \"flag[0]\", { \"min\": [1.99, -0.01, -0.01], \"max\": [2.01, 0.31, 0.01] }],\n"
    "  \"ports\": [\n"
    "    { \"name\": \"tip\", \"particle\": \"rope[5]\", \"kind\": \"force\" },\n"
    "    { \"name\": \"corner\", \"particle\": \"cloth[0,3]\", \"kind\": \"probe\" }\n"
    "  ],\n"
    "  \"simulation\": { \"stop_time\": 2.0, \"output_interval\": 0.05, \"solver\": \"klu\" }\n"
    "}\n";

typedef struct inputs {
	sm_document* document;
	sm_model* chain;              // 6 particles, the first fixed: dense LU, Adams
	sm_model* cloth_klu;          // 6 x 6, 34 free particles
	sm_model* cloth_jacobi;       // 8 x 8, 62 free: block Jacobi alone
	sm_model* cloth_two_level;    // 11 x 11, 119 free: two-level, exact coarse solve
	sm_model* cloth_multilevel;   // 12 x 12, 142 free: multilevel coarse solve
	sm_model* cloth_tearing;      // 6 x 6, soft springs that break under gravity
	sm_model* cloth_hanging;      // 7 x 7 hanging from its whole first row: statics and modes
	sm_sparse_jacobian* pattern;  // of cloth_hanging
	double* state;                // a configuration of cloth_hanging: x then v, 3 per particle each
} inputs;

static inputs in;

// A chain of `count` particles along x, the first fixed, springs of both kinds, mass damping.
static sm_model* make_chain(int32_t count)
{
	sm_model_def md = sm_default_model_def();
	md.mass_damping = 0.1;
	sm_model* model = sm_model_create(&md, NULL);
	if (model == NULL)
		return NULL;
	for (int32_t i = 0; i < count; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.mass = 0.5 + 0.1 * i;
		p.position[0] = 0.3 * i;
		p.velocity[1] = 0.2 * i;
		p.motion = i == 0 ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
		if (sm_model_add_particle(model, &p, NULL) != SM_OK)
			break;
		if (i == 0)
			continue;
		sm_spring_def s = sm_default_spring_def();
		s.a = i - 1;
		s.b = i;
		s.rest_length = 0.25;
		s.stiffness = 60.0;
		s.damping = 0.3;
		if (i % 3 == 0) {
			s.kind = SM_SPRING_ZERO_LENGTH;
			s.rest_length = 0.0;
		}
		if (sm_model_add_spring(model, &s, NULL) != SM_OK)
			break;
	}
	if (sm_model_particle_count(model) != count) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// An n x n cloth (the default sheet's constants, E [N] per strain) under gravity: in the z = 0
// plane held at the two corners of its first row or, with `hang_row`, hanging down from the whole
// row (near its equilibrium).
static sm_model* make_cloth(int32_t n, double stiffness, double break_strain, int hang_row)
{
	sm_model_def md = sm_default_model_def();
	sm_model* model = sm_model_create(&md, NULL);
	if (model == NULL)
		return NULL;
	sm_sheet_def sd = sm_default_sheet_def();
	sd.nu = n;
	sd.nv = n;
	sd.structural.stiffness = stiffness;
	sd.shear.stiffness = stiffness;
	sd.structural.break_strain = break_strain;
	if (hang_row) {
		sd.edge_v[1] = 0.0;
		sd.edge_v[2] = -1.0;
	}
	sm_structure st;
	sm_status status = sm_add_sheet(model, &sd, &st);
	if (status == SM_OK && hang_row) {
		const double lo[3] = {-0.01, -0.01, -0.01}, hi[3] = {1.01, 0.01, 0.01};
		status = sm_set_motion_in_box(model, lo, hi, SM_PARTICLE_FIXED, NULL);
	} else if (status == SM_OK) {
		status = sm_set_motion_at(model, &st, 0, 0, 0, SM_PARTICLE_FIXED);
		if (status == SM_OK)
			status = sm_set_motion_at(model, &st, 0, n - 1, 0, SM_PARTICLE_FIXED);
	}
	if (status != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

static int make_inputs(void)
{
	sm_error err;
	in.document = sm_document_parse(model_text, strlen(model_text), "threads.json", &err);
	if (in.document == NULL) {
		printf("  threads.json: %s\n", err.message);
		return 1;
	}
	in.chain = make_chain(6);
	in.cloth_klu = make_cloth(6, 1000.0, INFINITY, 0);
	in.cloth_jacobi = make_cloth(8, 1000.0, INFINITY, 0);
	in.cloth_two_level = make_cloth(11, 1000.0, INFINITY, 0);
	in.cloth_multilevel = make_cloth(12, 1000.0, INFINITY, 0);
	in.cloth_tearing = make_cloth(6, 30.0, 0.03, 0);
	in.cloth_hanging = make_cloth(7, 1000.0, INFINITY, 1);
	if (!in.chain || !in.cloth_klu || !in.cloth_jacobi || !in.cloth_two_level || !in.cloth_multilevel ||
	    !in.cloth_tearing || !in.cloth_hanging)
		return 1;
	in.pattern = sm_sparse_jacobian_create(in.cloth_hanging);
	const int32_t n = sm_model_particle_count(in.cloth_hanging);
	in.state = malloc(6 * (size_t)n * sizeof(double));
	if (in.pattern == NULL || in.state == NULL)
		return 1;
	// A deterministic configuration off the initial one: stretched and compressed springs,
	// moving particles.
	sm_model_initial_state(in.cloth_hanging, in.state, in.state + 3 * n);
	for (int32_t i = 0; i < 3 * n; i++) {
		in.state[i] += 0.02 * sin(1.7 * i);
		in.state[3 * n + i] = 0.3 * cos(0.9 * i);
	}
	return 0;
}

static void free_inputs(void)
{
	sm_document_destroy(in.document);
	sm_model_destroy(in.chain);
	sm_model_destroy(in.cloth_klu);
	sm_model_destroy(in.cloth_jacobi);
	sm_model_destroy(in.cloth_two_level);
	sm_model_destroy(in.cloth_multilevel);
	sm_model_destroy(in.cloth_tearing);
	sm_model_destroy(in.cloth_hanging);
	sm_sparse_jacobian_destroy(in.pattern);
	free(in.state);
}

// ---------------------------------------------------------------------------------------------
// The kinds of work. Each returns 0 and the hash of its results, or 1 (printing why).
// ---------------------------------------------------------------------------------------------

typedef enum work_kind {
	WORK_PARSE = 0,
	WORK_BUILD,
	WORK_DENSE,
	WORK_KLU,
	WORK_JACOBI,
	WORK_TWO_LEVEL,
	WORK_MULTILEVEL,
	WORK_MULTILEVEL_THREADS,
	WORK_CHOLMOD,
	WORK_ADAMS,
	WORK_BREAK,
	WORK_STATICS_DENSE,
	WORK_STATICS_SPARSE,
	WORK_MODES_DENSE,
	WORK_MODES_SPARSE,
	WORK_SPARSE_JACOBIAN,
	WORK_SAVE,
	WORK_COUNT
} work_kind;

static const char* const work_names[WORK_COUNT] = {"parse",
                                                   "build",
                                                   "dense",
                                                   "klu",
                                                   "pcg block Jacobi",
                                                   "pcg two-level",
                                                   "pcg multilevel",
                                                   "pcg multilevel on 2 threads",
                                                   "cholmod",
                                                   "adams",
                                                   "break",
                                                   "statics dense",
                                                   "statics sparse",
                                                   "modes dense",
                                                   "modes sparse",
                                                   "sparse jacobian",
                                                   "save"};

// ENSURE for the functions below, which free what they made: they start with `int failed = 1`,
// set it to 0 at the end of the work and free everything after the label `done`.
#define CHECK(cond)                                                                                          \
	do {                                                                                                     \
		if (!(cond)) {                                                                                       \
			printf("  %s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);                                \
			goto done;                                                                                       \
		}                                                                                                    \
	} while (0)

static int work_parse(uint64_t* h)
{
	int failed = 1;
	sm_error err;
	sm_model* model = NULL;
	sm_document* doc = sm_document_parse(model_text, strlen(model_text), "threads.json", &err);
	CHECK(doc != NULL);
	CHECK(sm_document_build(doc, &model, &err) == SM_OK);
	hash_model(h, model);
	for (int32_t i = 0; i < sm_model_particle_count(model); i++)
		hash_text(h, sm_document_particle_name(doc, i));
	for (int32_t i = 0; i < sm_document_parameter_count(doc); i++) {
		const double value = sm_document_parameter_value(doc, i);
		hash_text(h, sm_document_parameter_name(doc, i));
		hash_doubles(h, &value, 1);
	}
	for (int32_t i = 0; i < sm_document_port_count(doc); i++) {
		const sm_port port = sm_document_port(doc, i);
		hash_text(h, port.name);
		hash_int(h, port.particle);
		hash_int(h, port.kind);
	}
	const sm_document_settings settings = sm_document_get_settings(doc);
	hash_doubles(h, &settings.stop_time, 1);
	hash_doubles(h, &settings.output_interval, 1);
	hash_int(h, settings.solver.solver);
	hash_text(h, sm_document_name(doc));
	hash_text(h, sm_document_description(doc));
	// A parameter that changes counts: the rope grows from 5 to 7 segments.
	CHECK(sm_document_set_parameter(doc, sm_document_parameter_index(doc, "n"), 7.0, &err) == SM_OK);
	sm_model_destroy(model);
	model = NULL;
	CHECK(sm_document_build(doc, &model, &err) == SM_OK);
	hash_model(h, model);
	failed = 0;
done:
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return failed;
}

static int work_build(uint64_t* h)
{
	int failed = 1;
	sm_error err;
	sm_model* built = NULL;
	sm_model_def md = sm_default_model_def();
	sm_model* model = sm_model_create(&md, &err);
	CHECK(model != NULL);
	sm_rope_def rope = sm_default_rope_def();
	rope.segments = 12;
	rope.bending.stiffness = 30.0;
	sm_sheet_def sheet = sm_default_sheet_def();
	sheet.origin[1] = 2.0;
	sheet.nu = 7;
	sheet.nv = 5;
	sm_block_def block = sm_default_block_def();
	block.origin[0] = 3.0;
	block.nu = 3;
	static const double vertices[] = {0, 5, 0, 1, 5, 0, 0, 6, 0, 1, 6, 0.2, 0.5, 6.5, 0.1};
	static const int32_t triangles[] = {0, 1, 3, 0, 3, 2, 2, 3, 4};
	sm_mesh_def mesh = sm_default_mesh_def();
	mesh.vertices = vertices;
	mesh.vertex_count = 5;
	mesh.triangles = triangles;
	mesh.triangle_count = 3;
	mesh.bend.stiffness = 5.0;
	sm_structure st[4];
	CHECK(sm_add_rope(model, &rope, &st[0]) == SM_OK);
	CHECK(sm_add_sheet(model, &sheet, &st[1]) == SM_OK);
	CHECK(sm_add_block(model, &block, &st[2]) == SM_OK);
	CHECK(sm_add_mesh(model, &mesh, &st[3]) == SM_OK);
	const double lo[3] = {-0.1, -0.1, -0.1}, hi[3] = {0.1, 2.1, 0.1};
	int32_t moved = 0;
	CHECK(sm_set_motion_in_box(model, lo, hi, SM_PARTICLE_FIXED, &moved) == SM_OK);
	CHECK(sm_set_motion_at(model, &st[2], 1, 2, 3, SM_PARTICLE_DRIVEN) == SM_OK);
	const int32_t pins[2] = {st[3].first_particle, st[3].first_particle + 4};
	CHECK(sm_set_motion_of(model, pins, 2, SM_PARTICLE_FIXED) == SM_OK);
	hash_int(h, moved);
	hash_bytes(h, st, sizeof st);
	hash_model(h, model);
	CHECK(sm_document_build(in.document, &built, &err) == SM_OK);
	hash_model(h, built);
	failed = 0;
done:
	sm_model_destroy(built);
	sm_model_destroy(model);
	return failed;
}

// Simulates a shared model to t_end and hashes the state, the energies, the counters and the
// break events (wall-clock times left out); at least min_breaks springs must break.
static int simulate(const sm_model* model, sm_method method, sm_linear_solver solver, int32_t threads,
                    double t_end, int32_t min_breaks, uint64_t* h)
{
	int failed = 1;
	sm_error err;
	sm_simulation_def def = sm_default_simulation_def();
	def.method = method;
	def.solver = solver;
	def.threads = threads;
	sm_simulation* sim = sm_simulation_create(model, &def, &err);
	CHECK(sim != NULL);
	// Advance in a few calls, with an external force changed between them.
	const int32_t n = sm_model_particle_count(model);
	for (int k = 1; k <= 4; k++) {
		const double force[3] = {0.1 * k, 0.0, -0.05 * k};
		CHECK(sm_simulation_set_external_force(sim, n - 1, force) == SM_OK);
		if (sm_simulation_advance(sim, t_end * k / 4) != SM_OK) {
			printf("  advance: %s\n", sm_simulation_last_error(sim));
			goto done;
		}
	}
	hash_doubles(h, sm_simulation_positions(sim), 3 * (size_t)n);
	hash_doubles(h, sm_simulation_velocities(sim), 3 * (size_t)n);
	const sm_energies e = sm_simulation_energies(sim);
	const double energies[4] = {e.kinetic, e.elastic, e.gravity, sm_simulation_dissipated_energy(sim)};
	hash_doubles(h, energies, 4);
	const sm_statistics s = sm_simulation_statistics(sim);
	const int64_t counters[9] = {s.steps,
	                             s.rhs_evaluations,
	                             s.jacobian_evaluations,
	                             s.linear_iterations,
	                             s.error_test_failures,
	                             s.convergence_failures,
	                             s.restarts,
	                             s.factorizations,
	                             sm_simulation_solver(sim)};
	hash_bytes(h, counters, sizeof counters);
	CHECK(sm_simulation_break_count(sim) >= min_breaks);
	hash_int(h, sm_simulation_break_count(sim));
	for (int32_t i = 0; i < sm_simulation_break_count(sim); i++) {
		const sm_break_event b = sm_simulation_break(sim, i);
		hash_doubles(h, &b.time, 1);
		hash_int(h, b.spring);
	}
	failed = 0;
done:
	sm_simulation_destroy(sim);
	return failed;
}

static int statics(sm_statics_solver solver, uint64_t* h)
{
	int failed = 1;
	const int32_t n = sm_model_particle_count(in.cloth_hanging);
	double* x = malloc(6 * (size_t)n * sizeof(double));
	CHECK(x != NULL);
	sm_statics_def def = sm_default_statics_def();
	def.solver = solver;
	sm_statics_result result;
	sm_error err;
	if (sm_statics_solve(in.cloth_hanging, &def, x, x + 3 * n, &result, &err) != SM_OK) {
		printf("  statics: %s\n", err.message);
		goto done;
	}
	CHECK(result.solver == solver);
	hash_doubles(h, x, 6 * (size_t)n);
	const double numbers[7] = {result.residual,
	                           result.potential_energy,
	                           result.reaction_total[0],
	                           result.reaction_total[1],
	                           result.reaction_total[2],
	                           result.iterations,
	                           result.stable};
	hash_doubles(h, numbers, 7);
	failed = 0;
done:
	free(x);
	return failed;
}

static int modes(sm_modes_solver solver, uint64_t* h)
{
	sm_modes_def def = sm_default_modes_def();
	def.solver = solver;
	def.mode_count = 6;
	sm_modes m;
	sm_error err;
	if (sm_modes_compute(in.cloth_hanging, &def, &m, &err) != SM_OK) {
		printf("  modes: %s\n", err.message);
		return 1;
	}
	const sm_modes_solver used = m.solver;
	const size_t count = (size_t)m.count;
	hash_doubles(h, m.omega_squared, count);
	hash_doubles(h, m.frequency, count);
	hash_doubles(h, m.modal_damping, count);
	hash_doubles(h, m.damping_ratio, count);
	hash_doubles(h, m.shapes, count * 3 * (size_t)m.particle_count);
	const double summary[6] = {m.zero_count,       m.unstable_count, m.omega_max,
	                           m.damping_coupling, m.residual,       m.shift};
	hash_doubles(h, summary, 6);
	sm_modes_release(&m);
	if (used != solver || count != 6) {
		printf("  modes: solver %d, %d modes\n", (int)used, (int)count);
		return 1;
	}
	return 0;
}

// A pattern of its own and the shared one, filled at the shared state in both variants.
static int work_sparse_jacobian(uint64_t* h)
{
	int failed = 1;
	const sm_model* model = in.cloth_hanging;
	const int32_t n = sm_model_particle_count(model);
	double* values = NULL;
	sm_sparse_jacobian* own = sm_sparse_jacobian_create(model);
	CHECK(own != NULL);
	const int64_t dim = sm_sparse_jacobian_dimension(own);
	const int64_t nnz = sm_sparse_jacobian_nonzeros(own);
	CHECK(nnz == sm_sparse_jacobian_nonzeros(in.pattern));
	hash_bytes(h, sm_sparse_jacobian_row_pointers(own), (size_t)(dim + 1) * sizeof(int64_t));
	hash_bytes(h, sm_sparse_jacobian_column_indices(own), (size_t)nnz * sizeof(int64_t));
	values = malloc(2 * (size_t)nnz * sizeof(double));
	CHECK(values != NULL);
	for (int variant = SM_JACOBIAN_EXACT; variant <= SM_JACOBIAN_DEFINITE; variant++) {
		const sm_sparse_jacobian* patterns[2] = {own, in.pattern};
		for (int k = 0; k < 2; k++) {
			CHECK(sm_sparse_jacobian_fill(patterns[k], model, in.state, in.state + 3 * n,
			                              (sm_jacobian_variant)variant, values, values + nnz) == SM_OK);
			hash_doubles(h, values, 2 * (size_t)nnz);
		}
	}
	failed = 0;
done:
	free(values);
	sm_sparse_jacobian_destroy(own);
	return failed;
}

// The text and a file of the shared document; `slot` keeps the threads' files apart.
static int work_save(int slot, uint64_t* h)
{
	int failed = 1;
	sm_error err;
	char path[64];
	snprintf(path, sizeof path, "test_threads_save_%d.json", slot);
	char* text = sm_document_to_json(in.document, &err);
	char* saved = NULL;
	FILE* f = NULL;
	CHECK(text != NULL);
	CHECK(sm_document_save(in.document, path, &err) == SM_OK);
	const size_t length = strlen(text);
	saved = malloc(length + 2);
	CHECK(saved != NULL);
	f = fopen(path, "rb");
	CHECK(f != NULL);
	const size_t got = fread(saved, 1, length + 1, f);
	saved[got] = '\0';
	CHECK(got == length && memcmp(saved, text, length) == 0);
	hash_text(h, text);
	failed = 0;
done:
	if (f != NULL)
		fclose(f);
	remove(path);
	free(saved);
	free(text);
	return failed;
}

static int run_work(work_kind kind, int slot, uint64_t* hash)
{
	uint64_t h = 0xcbf29ce484222325u;
	int failed = 1;
	switch (kind) {
	case WORK_PARSE: failed = work_parse(&h); break;
	case WORK_BUILD: failed = work_build(&h); break;
	case WORK_DENSE: failed = simulate(in.chain, SM_METHOD_BDF, SM_SOLVER_DENSE, 1, 1.0, 0, &h); break;
	case WORK_KLU: failed = simulate(in.cloth_klu, SM_METHOD_BDF, SM_SOLVER_KLU, 1, 0.05, 0, &h); break;
	case WORK_JACOBI:
		failed = simulate(in.cloth_jacobi, SM_METHOD_BDF, SM_SOLVER_REDUCED_PCG, 1, 0.05, 0, &h);
		break;
	case WORK_TWO_LEVEL:
		failed = simulate(in.cloth_two_level, SM_METHOD_BDF, SM_SOLVER_REDUCED_PCG, 1, 0.02, 0, &h);
		break;
	case WORK_MULTILEVEL:
		failed = simulate(in.cloth_multilevel, SM_METHOD_BDF, SM_SOLVER_REDUCED_PCG, 1, 0.02, 0, &h);
		break;
	case WORK_MULTILEVEL_THREADS:
		failed = simulate(in.cloth_multilevel, SM_METHOD_BDF, SM_SOLVER_REDUCED_PCG, 2, 0.02, 0, &h);
		break;
	case WORK_CHOLMOD:
		failed = simulate(in.cloth_jacobi, SM_METHOD_BDF, SM_SOLVER_REDUCED_CHOLMOD, 1, 0.05, 0, &h);
		break;
	case WORK_ADAMS: failed = simulate(in.chain, SM_METHOD_ADAMS, SM_SOLVER_AUTO, 1, 1.0, 0, &h); break;
	case WORK_BREAK: failed = simulate(in.cloth_tearing, SM_METHOD_BDF, SM_SOLVER_AUTO, 1, 0.2, 2, &h); break;
	case WORK_STATICS_DENSE: failed = statics(SM_STATICS_DENSE, &h); break;
	case WORK_STATICS_SPARSE: failed = statics(SM_STATICS_SPARSE, &h); break;
	case WORK_MODES_DENSE: failed = modes(SM_MODES_DENSE, &h); break;
	case WORK_MODES_SPARSE: failed = modes(SM_MODES_SPARSE, &h); break;
	case WORK_SPARSE_JACOBIAN: failed = work_sparse_jacobian(&h); break;
	case WORK_SAVE: failed = work_save(slot, &h); break;
	default: break;
	}
	if (failed)
		printf("  %s (slot %d) failed\n", work_names[kind], slot);
	*hash = h;
	return failed;
}

// ---------------------------------------------------------------------------------------------
// Threads: released together by a barrier, each runs one piece of work.
// ---------------------------------------------------------------------------------------------

typedef struct task {
	work_kind kind;
	int slot;
	pthread_barrier_t* start;
	uint64_t hash;
	int failed;
} task;

static void* task_main(void* arg)
{
	task* t = arg;
	pthread_barrier_wait(t->start);
	t->failed = run_work(t->kind, t->slot, &t->hash);
	return NULL;
}

// The lone results, computed before any thread starts.
static uint64_t reference[WORK_COUNT];
static int reference_failed = 1;

// Runs the tasks at once; 0 if every one succeeded with its kind's lone hash.
static int run_tasks(task* tasks, int count)
{
	pthread_barrier_t start;
	pthread_t threads[WORK_COUNT * COPIES];
	ENSURE(count <= WORK_COUNT * COPIES);
	ENSURE(pthread_barrier_init(&start, NULL, (unsigned)count) == 0);
	int started = 0;
	for (; started < count; started++) {
		tasks[started].start = &start;
		if (pthread_create(&threads[started], NULL, task_main, &tasks[started]) != 0)
			break;
	}
	ENSURE(started == count);  // a barrier short of threads would never open
	for (int i = 0; i < count; i++)
		pthread_join(threads[i], NULL);
	pthread_barrier_destroy(&start);
	int wrong = 0;
	for (int i = 0; i < count; i++) {
		if (tasks[i].failed || tasks[i].hash != reference[tasks[i].kind]) {
			printf("  %s in thread %d: %s (hash %016llx, alone %016llx)\n", work_names[tasks[i].kind], i,
			       tasks[i].failed ? "failed" : "different bits", (unsigned long long)tasks[i].hash,
			       (unsigned long long)reference[tasks[i].kind]);
			wrong++;
		}
	}
	return wrong;
}

static int compute_references(void)
{
	for (int k = 0; k < WORK_COUNT; k++) {
		uint64_t again;
		if (run_work((work_kind)k, 0, &reference[k]) || run_work((work_kind)k, 0, &again))
			return 1;
		// The simulation on a team of 2 threads gives the bits of the lone thread's (the chunks
		// depend on the model alone).
		if (k == WORK_MULTILEVEL_THREADS && reference[k] != reference[WORK_MULTILEVEL]) {
			printf("  %s: other bits than on one thread\n", work_names[k]);
			return 1;
		}
		if (again != reference[k]) {
			printf("  %s: two lone runs differ (%016llx, %016llx)\n", work_names[k],
			       (unsigned long long)reference[k], (unsigned long long)again);
			return 1;
		}
	}
	return 0;
}

// COPIES threads doing the same work at once.
static int check_copies(work_kind kind)
{
	ENSURE(reference_failed == 0);
	task tasks[COPIES];
	for (int i = 0; i < COPIES; i++)
		tasks[i] = (task){.kind = kind, .slot = i};
	ENSURE(run_tasks(tasks, COPIES) == 0);
	return 0;
}

#define COPIES_TEST(name, kind)                                                                              \
	static int test_copies_##name(void)                                                                      \
	{                                                                                                        \
		return check_copies(kind);                                                                           \
	}
COPIES_TEST(parse, WORK_PARSE)
COPIES_TEST(build, WORK_BUILD)
COPIES_TEST(dense, WORK_DENSE)
COPIES_TEST(klu, WORK_KLU)
COPIES_TEST(pcg_block_jacobi, WORK_JACOBI)
COPIES_TEST(pcg_two_level, WORK_TWO_LEVEL)
COPIES_TEST(pcg_multilevel, WORK_MULTILEVEL)
COPIES_TEST(pcg_multilevel_on_threads, WORK_MULTILEVEL_THREADS)
COPIES_TEST(cholmod, WORK_CHOLMOD)
COPIES_TEST(adams, WORK_ADAMS)
COPIES_TEST(break_events, WORK_BREAK)
COPIES_TEST(statics_dense, WORK_STATICS_DENSE)
COPIES_TEST(statics_sparse, WORK_STATICS_SPARSE)
COPIES_TEST(modes_dense, WORK_MODES_DENSE)
COPIES_TEST(modes_sparse, WORK_MODES_SPARSE)
COPIES_TEST(sparse_jacobian, WORK_SPARSE_JACOBIAN)
COPIES_TEST(save, WORK_SAVE)

// Every kind at once, MIXED_COPIES threads each, interleaved so that neighbours differ.
static int test_mixed(void)
{
	ENSURE(reference_failed == 0);
	task tasks[WORK_COUNT * MIXED_COPIES];
	int count = 0;
	for (int c = 0; c < MIXED_COPIES; c++)
		for (int k = 0; k < WORK_COUNT; k++) {
			const work_kind kind = (work_kind)(c % 2 == 0 ? k : WORK_COUNT - 1 - k);
			tasks[count] = (task){.kind = kind, .slot = 100 + count};
			count++;
		}
	ENSURE(run_tasks(tasks, count) == 0);
	return 0;
}

// The threads of this process (its entries in /proc/self/task, less "." and ".."); -1 if unknown.
static int process_threads(void)
{
	DIR* d = opendir("/proc/self/task");
	if (d == NULL)
		return -1;
	int count = 0;
	for (const struct dirent* e; (e = readdir(d)) != NULL;)
		count += e->d_name[0] != '.';
	closedir(d);
	return count;
}

// A simulation's threads (docs/simulation.md): on a model in chunks, `threads` = 8 starts at most
// 4 (the caller's included) and no more than the processors the process may run on, when the
// simulation is made. The 12 x 12 cloth runs in chunks in this build. Run first, while no thread
// of another test may still be ending (a joined thread can stay listed for a moment).
static int test_simulation_threads_are_capped(void)
{
	const int before = process_threads();
	if (before < 0) {
		printf("  no /proc/self/task: skipped\n");
		return 0;
	}
	const int processors = sm_workers_processors(), most = processors < 4 ? processors : 4;
	sm_error err;
	sm_simulation_def def = sm_default_simulation_def();
	def.solver = SM_SOLVER_REDUCED_PCG;
	def.threads = 8;
	sm_simulation* sim = sm_simulation_create(in.cloth_multilevel, &def, &err);
	ENSURE(sim != NULL);
	ENSURE(process_threads() == before + most - 1);
	ENSURE(sm_simulation_advance(sim, 0.01) == SM_OK);
	sm_simulation_destroy(sim);
	return 0;
}

// A child of fork() has only the thread that forked: a team started before the fork runs its
// chunks on the child's thread instead of waiting for helpers that are not there. A hang would
// end the child by SIGALRM after 10 s.
typedef struct count_job {
	int done[8];
} count_job;

static void count_chunk(void* context, int c)
{
	((count_job*)context)->done[c]++;
}

static int test_team_in_a_forked_child(void)
{
	sm_workers* team = sm_workers_create(2);
	ENSURE(team != NULL);
	count_job job = {{0}};
	sm_workers_run(team, count_chunk, &job, 8);
	fflush(stdout);
	const pid_t child = fork();
	ENSURE(child >= 0);
	if (child == 0) {
		alarm(10);
		count_job mine = {{0}};
		sm_workers_run(team, count_chunk, &mine, 8);
		int ok = 1;
		for (int c = 0; c < 8; c++)
			ok = ok && mine.done[c] == 1;
		_exit(ok ? 0 : 1);
	}
	int status = 0;
	ENSURE(waitpid(child, &status, 0) == child);
	ENSURE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
	sm_workers_run(team, count_chunk, &job, 8);  // the parent's team still works
	for (int c = 0; c < 8; c++)
		ENSURE(job.done[c] == 2);
	sm_workers_destroy(team);
	return 0;
}

// The child of a fork() destroys its copy of a team (as it does destroying a simulation, or
// updating the model of one on the multilevel path) without waiting for the parent's helpers,
// which it does not have: forked while they slept, joining them or destroying the condition
// variable they waited on hung the child until SIGALRM ended it after 10 s.
static int test_team_destroyed_in_a_forked_child(void)
{
	sm_workers* team = sm_workers_create(2);
	ENSURE(team != NULL);
	count_job job = {{0}};
	sm_workers_run(team, count_chunk, &job, 8);
	// The helpers go to sleep after about 0.1 ms without work.
	const struct timespec pause = {0, 50 * 1000 * 1000};
	nanosleep(&pause, NULL);
	fflush(stdout);
	const pid_t child = fork();
	ENSURE(child >= 0);
	if (child == 0) {
		alarm(10);
		count_job mine = {{0}};
		sm_workers_run(team, count_chunk, &mine, 8);
		sm_workers_destroy(team);
		_exit(mine.done[7] == 1 ? 0 : 1);
	}
	int status = 0;
	ENSURE(waitpid(child, &status, 0) == child);
	ENSURE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
	sm_workers_run(team, count_chunk, &job, 8);  // the parent's team still works
	ENSURE(job.done[7] == 2);
	sm_workers_destroy(team);
	return 0;
}

// Chunks are claimed, not dealt out: a thread takes the next chunk left whenever it is free, so
// the caller does the work of a helper that does not get to run (processors busy elsewhere) rather
// than wait for it. Shown with a job whose chunk 0 waits until chunks 1 to 3 are done: whichever
// thread claims chunk 0, another must claim all three others (dealt out round-robin to 2
// threads, chunk 2 would wait behind chunk 0 on the same thread forever, and the test would
// hang until ctest's time limit for it ends it).
typedef struct waiting_job {
	atomic_int finished;
} waiting_job;

static void waiting_chunk(void* context, int c)
{
	waiting_job* j = context;
	if (c == 0)
		while (atomic_load(&j->finished) < 3)
			sched_yield();
	else
		atomic_fetch_add(&j->finished, 1);
}

static int test_chunks_are_claimed_by_free_threads(void)
{
	sm_workers* team = sm_workers_create(2);
	ENSURE(team != NULL);
	for (int k = 0; k < 100; k++) {
		waiting_job job;
		atomic_init(&job.finished, 0);
		sm_workers_run(team, waiting_chunk, &job, 4);
		ENSURE(atomic_load(&job.finished) == 3);
	}
	sm_workers_destroy(team);
	return 0;
}

// The helpers block every signal, so that a signal for the process reaches one of the program's
// own threads (the caller here blocks none of SIGINT, SIGTERM, SIGUSR1). Chunk 0 waits for the
// others, so at least one chunk runs on the helper.
typedef struct mask_job {
	waiting_job wait;
	pthread_t caller;
	bool on_helper[4];
	bool blocked[4];
} mask_job;

static void mask_chunk(void* context, int c)
{
	mask_job* j = context;
	sigset_t mask;
	pthread_sigmask(SIG_BLOCK, NULL, &mask);
	j->on_helper[c] = !pthread_equal(pthread_self(), j->caller);
	j->blocked[c] = sigismember(&mask, SIGINT) && sigismember(&mask, SIGTERM) && sigismember(&mask, SIGUSR1);
	waiting_chunk(&j->wait, c);
}

static int test_helpers_block_signals(void)
{
	sigset_t none;
	sigemptyset(&none);
	ENSURE(pthread_sigmask(SIG_SETMASK, &none, NULL) == 0);
	sm_workers* team = sm_workers_create(2);
	ENSURE(team != NULL);
	mask_job job = {.caller = pthread_self()};
	atomic_init(&job.wait.finished, 0);
	sm_workers_run(team, mask_chunk, &job, 4);
	sm_workers_destroy(team);
	int on_helper = 0;
	for (int c = 0; c < 4; c++) {
		ENSURE(job.blocked[c] == job.on_helper[c]);
		on_helper += job.on_helper[c];
	}
	ENSURE(on_helper >= 1);
	return 0;
}

// Floating-point exceptions raised in a helper's chunk reach the caller's flags, as they would
// if the caller had run the chunk: chunk 0 divides by zero and waits for chunk 1, which
// overflows, so that each of the two threads runs one chunk; both flags must be set afterwards.
// They belong to that job alone: the next job, whose chunks raise nothing, leaves the caller's
// flags clear, as it would run alone.
typedef struct raising_job {
	waiting_job wait;
	volatile double zero, huge;
	double result[2];
} raising_job;

static void raising_chunk(void* context, int c)
{
	raising_job* j = context;
	if (c == 0) {
		j->result[0] = 1.0 / j->zero;
		while (atomic_load(&j->wait.finished) < 1)
			sched_yield();
	} else {
		j->result[1] = j->huge * 2.0;
		atomic_fetch_add(&j->wait.finished, 1);
	}
}

static int test_exceptions_raised_in_helpers_reach_the_caller(void)
{
	sm_workers* team = sm_workers_create(2);
	ENSURE(team != NULL);
	for (int k = 0; k < 20; k++) {
		raising_job job = {.zero = 0.0, .huge = DBL_MAX};
		atomic_init(&job.wait.finished, 0);
		feclearexcept(FE_ALL_EXCEPT);
		sm_workers_run(team, raising_chunk, &job, 2);
		ENSURE(fetestexcept(FE_DIVBYZERO) && fetestexcept(FE_OVERFLOW));
		ENSURE(isinf(job.result[0]) && isinf(job.result[1]));
		feclearexcept(FE_ALL_EXCEPT);
		count_job quiet = {{0}};
		sm_workers_run(team, count_chunk, &quiet, 8);
		ENSURE(!fetestexcept(FE_DIVBYZERO | FE_OVERFLOW) && quiet.done[7] == 1);
	}
	feclearexcept(FE_ALL_EXCEPT);
	sm_workers_destroy(team);
	return 0;
}

// A locale with a decimal comma (freelocale it), or (locale_t)0 where none is installed.
static locale_t decimal_comma_locale(void)
{
	static const char* const names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8",
	                                    "nl_NL.UTF-8"};
	locale_t comma = (locale_t)0;
	for (size_t k = 0; k < sizeof names / sizeof names[0] && comma == (locale_t)0; k++)
		comma = newlocale(LC_ALL_MASK, names[k], (locale_t)0);
	return comma;
}

// The program's locale is process-wide state the library must not depend on: saving in a thread
// whose locale has a decimal comma gives the same text (it was "9,81" for 9.81, not JSON), and
// leaves that thread's locale as it was. Skipped where no such locale is installed.
static int test_save_in_a_decimal_comma_locale(void)
{
	ENSURE(reference_failed == 0);
	const locale_t comma = decimal_comma_locale();
	if (comma == (locale_t)0) {
		printf("  no locale with a decimal comma is installed: skipped\n");
		return 0;
	}
	const locale_t previous = uselocale(comma);
	char check[16];
	snprintf(check, sizeof check, "%.2f", 9.81);
	uint64_t hash;
	const int failed = run_work(WORK_SAVE, 0, &hash);
	const locale_t after = uselocale(previous);
	freelocale(comma);
	ENSURE(strcmp(check, "9,81") == 0);
	ENSURE(after == comma);
	ENSURE(failed == 0);
	ENSURE(hash == reference[WORK_SAVE]);
	return 0;
}

// Parsing where two threads' locales differ: glibc's localeconv(), which the JSON parser asks
// for the decimal point before it reads each real number, fills one static structure for the
// whole process, so a thread under a decimal comma read the other thread's '.' (or it the comma)
// and the parser aborted the process on "9.81" read as 9. A thread under a decimal comma and one
// in the C locale parse the same text of many real numbers at once, again and again; every parse
// gives the model a lone parse gives, to the bit.
enum { LOCALE_PARSES = 300, LOCALE_PARTICLES = 100 };

typedef struct locale_parses {
	locale_t locale;  // (locale_t)0: the thread keeps the program's
	pthread_barrier_t* start;
	const char* text;
	uint64_t alone;  // the hash of the model parsed alone
	int wrong;
} locale_parses;

// The hash of the model in text, 0 if it cannot be parsed.
static uint64_t parsed_model_hash(const char* text)
{
	sm_error err;
	sm_model* model = NULL;
	sm_document* doc = sm_document_parse(text, strlen(text), "reals.json", &err);
	uint64_t h = 0;
	if (doc != NULL && sm_document_build(doc, &model, &err) == SM_OK) {
		h = 0xcbf29ce484222325u;
		hash_model(&h, model);
	}
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return h;
}

static void* parse_in_locale(void* arg)
{
	locale_parses* p = arg;
	const locale_t previous = p->locale != (locale_t)0 ? uselocale(p->locale) : (locale_t)0;
	pthread_barrier_wait(p->start);
	for (int k = 0; k < LOCALE_PARSES; k++)
		p->wrong += parsed_model_hash(p->text) != p->alone;
	if (p->locale != (locale_t)0)
		uselocale(previous);
	return NULL;
}

static int test_parse_in_threads_of_different_locales(void)
{
	const locale_t comma = decimal_comma_locale();
	if (comma == (locale_t)0) {
		printf("  no locale with a decimal comma is installed: skipped\n");
		return 0;
	}
	// A chain of particles at positions, with masses and velocities, of fractional metres.
	static char text[LOCALE_PARTICLES * 120 + 200];
	int at =
	    snprintf(text, sizeof text,
		         "{\"springmass\": 1, \"name\": \"reals\", \"gravity\": [0, 0, -9.81], \"particles\": [");
	for (int i = 0; i < LOCALE_PARTICLES; i++)
		at += snprintf(text + at, sizeof text - (size_t)at,
		               "%s{\"position\": [%d.25, %d.125, 0.75], \"velocity\": [0.5, %d.375, 0.0625], "
		               "\"mass\": %d.5}",
		               i > 0 ? ", " : "", i, 2 * i, i, 1 + i % 3);
	snprintf(text + at, sizeof text - (size_t)at, "]}");
	const uint64_t alone = parsed_model_hash(text);
	pthread_barrier_t start;
	int started = 0;
	pthread_t threads[2];
	locale_parses runs[2] = {{.locale = comma, .text = text, .alone = alone},
	                         {.locale = (locale_t)0, .text = text, .alone = alone}};
	if (alone != 0 && pthread_barrier_init(&start, NULL, 2) == 0) {
		runs[0].start = runs[1].start = &start;
		while (started < 2 && pthread_create(&threads[started], NULL, parse_in_locale, &runs[started]) == 0)
			started++;
		if (started == 1)  // the barrier would never open: release the thread that waits
			pthread_barrier_wait(&start);
		for (int t = 0; t < started; t++)
			pthread_join(threads[t], NULL);
		pthread_barrier_destroy(&start);
	}
	freelocale(comma);
	ENSURE(alone != 0);
	ENSURE(started == 2);
	ENSURE(runs[0].wrong == 0);
	ENSURE(runs[1].wrong == 0);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	if (make_inputs() != 0) {
		printf("the inputs could not be made\n");
		free_inputs();
		return 1;
	}
	reference_failed = compute_references();
	if (reference_failed)
		printf("the lone runs failed: every test below fails\n");
	RUN_TEST(test_simulation_threads_are_capped);
	RUN_TEST(test_copies_parse);
	RUN_TEST(test_copies_build);
	RUN_TEST(test_copies_dense);
	RUN_TEST(test_copies_klu);
	RUN_TEST(test_copies_pcg_block_jacobi);
	RUN_TEST(test_copies_pcg_two_level);
	RUN_TEST(test_copies_pcg_multilevel);
	RUN_TEST(test_copies_pcg_multilevel_on_threads);
	RUN_TEST(test_copies_cholmod);
	RUN_TEST(test_copies_adams);
	RUN_TEST(test_copies_break_events);
	RUN_TEST(test_copies_statics_dense);
	RUN_TEST(test_copies_statics_sparse);
	RUN_TEST(test_copies_modes_dense);
	RUN_TEST(test_copies_modes_sparse);
	RUN_TEST(test_copies_sparse_jacobian);
	RUN_TEST(test_copies_save);
	RUN_TEST(test_mixed);
	RUN_TEST(test_team_in_a_forked_child);
	RUN_TEST(test_team_destroyed_in_a_forked_child);
	RUN_TEST(test_chunks_are_claimed_by_free_threads);
	RUN_TEST(test_exceptions_raised_in_helpers_reach_the_caller);
	RUN_TEST(test_helpers_block_signals);
	RUN_TEST(test_save_in_a_decimal_comma_locale);
	RUN_TEST(test_parse_in_threads_of_different_locales);
	free_inputs();
	return TEST_SUMMARY();
}

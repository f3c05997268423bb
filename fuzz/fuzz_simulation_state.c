// libFuzzer target for simulation states read back from bytes (sm_simulation_state_deserialize)
// and restored into a running simulation (sm_simulation_restore_state), as an FMI master's
// serialised FMU state or a checkpoint file is: untrusted bytes. Any input must be refused with
// a message, or read back to a snapshot that writes the same bytes again; a restore must either
// be refused with a message and the simulation unchanged, or take the snapshot as it is, after
// which a short advance ends with finite positions and velocities or with an error that says why.
// Either way, restored to a known state afterwards, the simulation advances from it bit for bit as
// it did before any input: a restore starts afresh, so nothing of an input reaches the next.
//
// The input is one control byte and then the bytes of a state:
//   bit 0     keep the checksum as given (else it is recomputed over the mutated bytes, since
//             random bytes would almost never pass it and the checks behind it would go unfuzzed)
//   bits 1-3  which simulation restores it (one per linear solver, and Adams), modulo their count
//   bit 4     advance with sm_simulation_advance_interpolated rather than sm_simulation_advance
//
// With SPRINGMASS_FUZZ_WRITE_SEEDS set to a folder, the target writes real states of its own model
// and of a model of other sizes there as seeds (fuzz/run.sh does) and exits.
#include "springmass/springmass.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int* argc, char*** argv);
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

#define PARTICLES 4
#define SPRINGS 5
#define SIMULATIONS 5
#define CONTROL_KEEP_CHECKSUM 0x01u
#define CONTROL_INTERPOLATED 0x10u
#define CONTROL_SIMULATION(k) ((unsigned)(k) << 1)
// The advance after a restore [s]: a few steps of the model, enough to reach the solver's set-up,
// its Newton iterations and the root functions of the breakable springs.
#define ADVANCE 1e-3
// Internal steps allowed per advance. The default, 100000, took 0.7 s (15 s under the sanitizers)
// for a state of forces near 1e174 N, to end at the step limit with a clean error as documented;
// the same path is reached with fewer steps, and the fuzzer keeps its pace.
#define MAX_STEPS 2000
// The serialised header (serialized_header in lib/simulation_state.c): 48 bytes, of which bytes
// 28 to 31 are reserved (written as 0, not read) and 32 to 39 the model's topology hash; the
// 8-byte checksum ends the state.
#define HEADER_BYTES 48
#define RESERVED_OFFSET 28
#define RESERVED_END 32
#define TOPOLOGY_OFFSET 32
#define CHECKSUM_BYTES 8

// What every input runs against: the model, one simulation per linear solver, and the state each
// simulation is put back into before an input, so that what an input does depends on it alone,
// not on the inputs before it (a restore starts the solver as new). libFuzzer's entry point has no
// context argument, so the fixture is a file-scope pointer, set once in LLVMFuzzerInitialize: the
// library's rule against global state is for the library, which this program only calls.
typedef struct fixture {
	sm_model* model;
	sm_simulation* simulations[SIMULATIONS];
	unsigned char* baseline;  // a serialised state of the model at 0.05 s
	size_t baseline_size;
	// Where each simulation got in an advance of ADVANCE from the baseline, before any input:
	// every restore continues alike, so an input leaves nothing behind that changes the next.
	double reference_position[SIMULATIONS][3 * PARTICLES], reference_velocity[SIMULATIONS][3 * PARTICLES];
	double reference_dissipated[SIMULATIONS];
} fixture;

static fixture* the_fixture;

// 64-bit FNV-1a over all bytes but the last 8, the checksum as the serialised form defines it
// (lib/simulation_state.c, above serialized_header). The library's own function is a static helper
// of simulation_state.c with no internal header; the format fixes the hash, as the tests' forged
// states assume, so the target computes it itself rather than widen the library for it.
// Initialisation checks it against a state the library wrote, so that a change of the format stops
// the target instead of leaving it to fuzz the checksum test alone.
static uint64_t state_checksum(const unsigned char* bytes, size_t size)
{
	uint64_t h = 14695981039346656037ull;
	for (size_t k = 0; k + CHECKSUM_BYTES < size; k++)
		h = (h ^ bytes[k]) * 1099511628211ull;
	return h;
}

// The model, with content in every section of a state: particle 0 fixed, 1 driven (moving away
// along x at 0.5 m/s), 2 and 3 free under gravity; spring 0 from 0 to 1 breaks at 10 % strain
// (at 0.2 s), spring 2 from 1 to 3 at 50 %, spring 4 is of zero length. The external force on
// particle 3 is set on each simulation.
static sm_model* build_model(void)
{
	sm_model_def md = sm_default_model_def();
	md.mass_damping = 0.1;
	sm_model* model = sm_model_create(&md, NULL);
	if (model == NULL)
		return NULL;
	const double at[PARTICLES][3] = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.0, -0.5}, {1.0, 0.0, -0.5}};
	const sm_particle_motion motion[PARTICLES] = {SM_PARTICLE_FIXED, SM_PARTICLE_DRIVEN, SM_PARTICLE_FREE,
	                                              SM_PARTICLE_FREE};
	bool ok = true;
	for (int i = 0; ok && i < PARTICLES; i++) {
		sm_particle_def p = sm_default_particle_def();
		memcpy(p.position, at[i], sizeof p.position);
		p.motion = motion[i];
		p.mass = 0.5 + 0.25 * i;
		if (motion[i] == SM_PARTICLE_DRIVEN)
			p.velocity[0] = 0.5;
		ok = sm_model_add_particle(model, &p, NULL) == SM_OK;
	}
	const int32_t ends[SPRINGS][2] = {{0, 1}, {0, 2}, {1, 3}, {2, 3}, {0, 3}};
	const double break_strain[SPRINGS] = {0.1, INFINITY, 0.5, INFINITY, INFINITY};
	for (int s = 0; ok && s < SPRINGS; s++) {
		sm_spring_def d = sm_default_spring_def();
		d.a = ends[s][0];
		d.b = ends[s][1];
		d.stiffness = 100.0;
		d.damping = 1.0;
		d.break_strain = break_strain[s];
		if (s == SPRINGS - 1) {
			d.kind = SM_SPRING_ZERO_LENGTH;
			d.rest_length = 0.0;
			d.stiffness = 5.0;
		}
		ok = sm_model_add_spring(model, &d, NULL) == SM_OK;
	}
	if (!ok) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// A model of other sizes for seeds: a chain of 3 particles from a fixed one, 2 springs.
static sm_model* build_other_model(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* model = sm_model_create(&md, NULL);
	bool ok = model != NULL;
	for (int i = 0; ok && i < 3; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.position[0] = 0.5 * i;
		p.motion = i == 0 ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
		ok = sm_model_add_particle(model, &p, NULL) == SM_OK;
	}
	for (int s = 0; ok && s < 2; s++) {
		sm_spring_def d = sm_default_spring_def();
		d.a = s;
		d.b = s + 1;
		d.stiffness = 50.0;
		ok = sm_model_add_spring(model, &d, NULL) == SM_OK;
	}
	if (!ok) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

static sm_simulation* build_simulation(const sm_model* model, int which)
{
	sm_simulation_def d = sm_default_simulation_def();
	const sm_linear_solver solvers[SIMULATIONS] = {SM_SOLVER_DENSE, SM_SOLVER_KLU, SM_SOLVER_REDUCED_PCG,
	                                               SM_SOLVER_REDUCED_CHOLMOD, SM_SOLVER_DENSE};
	d.solver = solvers[which];
	d.max_steps = MAX_STEPS;
	if (which == SIMULATIONS - 1)
		d.method = SM_METHOD_ADAMS;
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	const double force[3] = {0.0, 1.0, 0.0};
	if (sim != NULL && sm_simulation_set_external_force(sim, 3, force) != SM_OK) {
		sm_simulation_destroy(sim);
		return NULL;
	}
	return sim;
}

// The simulation's state as bytes (malloc'd, *size set), NULL if memory runs out.
static unsigned char* serialized_state(const sm_simulation* sim, size_t* size)
{
	sm_simulation_state* s = sm_simulation_save_state(sim);
	*size = sm_simulation_state_size(s);
	unsigned char* bytes = s != NULL ? malloc(*size) : NULL;
	if (bytes != NULL && sm_simulation_state_serialize(s, bytes, *size) != SM_OK) {
		free(bytes);
		bytes = NULL;
	}
	sm_simulation_state_destroy(s);
	return bytes;
}

// A state of the simulation at each stage of a run, as a seed file in `folder` with the given
// control byte; with `topology` given, the state claims it for its model's (its checksum written
// again).
static void write_seed(const sm_simulation* sim, const char* folder, int number, unsigned control,
                       const unsigned char* topology)
{
	size_t size = 0;
	unsigned char* bytes = serialized_state(sim, &size);
	if (bytes != NULL && topology != NULL) {
		memcpy(bytes + TOPOLOGY_OFFSET, topology, 8);
		const uint64_t h = state_checksum(bytes, size);
		memcpy(bytes + size - CHECKSUM_BYTES, &h, CHECKSUM_BYTES);
	}
	char path[4096];
	snprintf(path, sizeof path, "%s/state-%d", folder, number);
	const unsigned char first = (unsigned char)control;
	FILE* f = bytes != NULL ? fopen(path, "wb") : NULL;
	if (f == NULL || fwrite(&first, 1, 1, f) != 1 || fwrite(bytes, 1, size, f) != size || fclose(f) != 0) {
		fprintf(stderr, "fuzz_simulation_state: cannot write %s\n", path);
		exit(1);
	}
	free(bytes);
}

// Seeds from one run of the model: at the start, under way, after the driven particle was set
// moving otherwise (its drive time no longer 0), after spring 0 broke at its strain and after
// spring 3 was cut (two break events); each with another simulation and advance, and one with its
// checksum kept.
static void write_seeds(const sm_model* model, const char* folder)
{
	sm_simulation* sim = build_simulation(model, 0);
	if (sim == NULL)
		exit(1);
	const double position[3] = {1.05, 0.0, 0.0}, velocity[3] = {0.6, 0.0, 0.1};
	write_seed(sim, folder, 0, CONTROL_SIMULATION(0), NULL);
	bool ok = sm_simulation_advance(sim, 0.05) == SM_OK;
	write_seed(sim, folder, 1, CONTROL_SIMULATION(1), NULL);
	write_seed(sim, folder, 2, CONTROL_SIMULATION(0) | CONTROL_KEEP_CHECKSUM, NULL);
	ok = ok && sm_simulation_set_driven(sim, 1, position, velocity) == SM_OK &&
	     sm_simulation_advance(sim, 0.12) == SM_OK;
	write_seed(sim, folder, 3, CONTROL_SIMULATION(2) | CONTROL_INTERPOLATED, NULL);
	ok = ok && sm_simulation_advance(sim, 0.3) == SM_OK && sm_simulation_break_count(sim) > 0;
	write_seed(sim, folder, 4, CONTROL_SIMULATION(3), NULL);
	ok = ok && sm_simulation_break_spring(sim, 3) == SM_OK && sm_simulation_advance(sim, 0.35) == SM_OK;
	write_seed(sim, folder, 5, CONTROL_SIMULATION(4) | CONTROL_INTERPOLATED, NULL);
	// A state of a model of other sizes (3 particles, 2 springs) under way, as it is and claiming
	// the topology of the target's model: a restore must refuse either, by the hash or by the counts.
	size_t size = 0;
	unsigned char* own = serialized_state(sim, &size);
	sm_simulation_destroy(sim);
	sm_model* other = build_other_model();
	sim = other != NULL && own != NULL ? sm_simulation_create(other, NULL, NULL) : NULL;
	ok = ok && sim != NULL && sm_simulation_advance(sim, 0.05) == SM_OK;
	if (ok) {
		write_seed(sim, folder, 6, CONTROL_SIMULATION(0), NULL);
		write_seed(sim, folder, 7, CONTROL_SIMULATION(1), own + TOPOLOGY_OFFSET);
	}
	free(own);
	sm_simulation_destroy(sim);
	sm_model_destroy(other);
	if (!ok) {
		fprintf(stderr, "fuzz_simulation_state: the seed run failed\n");
		exit(1);
	}
}

int LLVMFuzzerInitialize(int* argc, char*** argv)
{
	(void)argc;
	(void)argv;
	fixture* f = calloc(1, sizeof *f);
	if (f == NULL || (f->model = build_model()) == NULL)
		abort();
	const char* seeds = getenv("SPRINGMASS_FUZZ_WRITE_SEEDS");
	if (seeds != NULL && seeds[0] != '\0') {
		write_seeds(f->model, seeds);
		sm_model_destroy(f->model);
		free(f);
		exit(0);
	}
	for (int k = 0; k < SIMULATIONS; k++)
		if ((f->simulations[k] = build_simulation(f->model, k)) == NULL)
			abort();
	if (sm_simulation_advance(f->simulations[0], 0.05) != SM_OK)
		abort();
	f->baseline = serialized_state(f->simulations[0], &f->baseline_size);
	if (f->baseline == NULL)
		abort();
	uint64_t written;
	memcpy(&written, f->baseline + f->baseline_size - CHECKSUM_BYTES, CHECKSUM_BYTES);
	if (written != state_checksum(f->baseline, f->baseline_size)) {
		fprintf(stderr,
		        "fuzz_simulation_state: the state's checksum is no longer FNV-1a; update the target\n");
		abort();
	}
	for (int k = 0; k < SIMULATIONS; k++) {
		sm_simulation* sim = f->simulations[k];
		sm_simulation_state* s = sm_simulation_state_deserialize(f->baseline, f->baseline_size, NULL);
		if (s == NULL || sm_simulation_restore_state(sim, s) != SM_OK ||
		    sm_simulation_advance(sim, sm_simulation_time(sim) + ADVANCE) != SM_OK)
			abort();
		sm_simulation_state_destroy(s);
		memcpy(f->reference_position[k], sm_simulation_positions(sim), sizeof f->reference_position[k]);
		memcpy(f->reference_velocity[k], sm_simulation_velocities(sim), sizeof f->reference_velocity[k]);
		f->reference_dissipated[k] = sm_simulation_dissipated_energy(sim);
	}
	the_fixture = f;
	return 0;
}

// Whether all 3 n positions and velocities are finite.
static bool finite_motion(const sm_simulation* sim)
{
	const double* x = sm_simulation_positions(sim);
	const double* v = sm_simulation_velocities(sim);
	for (int k = 0; k < 3 * PARTICLES; k++)
		if (!isfinite(x[k]) || !isfinite(v[k]))
			return false;
	return true;
}

// What a caller can see of a simulation's state: its snapshot as bytes, the positions and
// velocities derived from it, and which springs are intact.
typedef struct observed {
	unsigned char* state;
	size_t size;
	double position[3 * PARTICLES], velocity[3 * PARTICLES];
	bool enabled[SPRINGS];
} observed;

static observed observe(const sm_simulation* sim)
{
	observed o;
	o.state = serialized_state(sim, &o.size);
	if (o.state == NULL)
		abort();
	memcpy(o.position, sm_simulation_positions(sim), sizeof o.position);
	memcpy(o.velocity, sm_simulation_velocities(sim), sizeof o.velocity);
	for (int s = 0; s < SPRINGS; s++)
		o.enabled[s] = sm_model_spring_enabled(sm_simulation_model(sim), s);
	return o;
}

static bool same(const observed* a, const observed* b)
{
	return a->size == b->size && memcmp(a->state, b->state, a->size) == 0 &&
	       memcmp(a->position, b->position, sizeof a->position) == 0 &&
	       memcmp(a->velocity, b->velocity, sizeof a->velocity) == 0 &&
	       memcmp(a->enabled, b->enabled, sizeof a->enabled) == 0;
}

static void fail(const char* what, const char* message)
{
	fprintf(stderr, "fuzz_simulation_state: %s%s%s\n", what, message ? ": " : "", message ? message : "");
	abort();
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	fixture* f = the_fixture;
	if (size < 1)
		return 0;
	const unsigned control = data[0];
	const size_t n = size - 1;
	unsigned char* bytes = malloc(n > 0 ? n : 1);
	if (bytes == NULL)
		abort();
	memcpy(bytes, data + 1, n);
	if (!(control & CONTROL_KEEP_CHECKSUM) && n >= CHECKSUM_BYTES) {
		const uint64_t h = state_checksum(bytes, n);
		memcpy(bytes + n - CHECKSUM_BYTES, &h, CHECKSUM_BYTES);
	}
	sm_error err = {SM_OK, ""};
	sm_simulation_state* state = sm_simulation_state_deserialize(bytes, n, &err);
	if (state == NULL) {
		if (err.status == SM_OK || err.message[0] == '\0')
			fail("deserialize refused the bytes without saying why", NULL);
		free(bytes);
		return 0;
	}
	// Read back, the snapshot writes the bytes it came from, but for the header's reserved field
	// (written as 0) and so the checksum.
	unsigned char* again = malloc(n);
	if (again == NULL)
		abort();
	if (err.status != SM_OK || sm_simulation_state_size(state) != n ||
	    sm_simulation_state_serialize(state, again, n) != SM_OK)
		fail("a state read back does not write its size", NULL);
	if (memcmp(again, bytes, RESERVED_OFFSET) != 0 ||
	    memcmp(again + RESERVED_END, bytes + RESERVED_END, n - RESERVED_END - CHECKSUM_BYTES) != 0)
		fail("a state read back writes other bytes", NULL);
	free(again);

	const int which = (int)((control >> 1 & 7u) % SIMULATIONS);
	sm_simulation* sim = f->simulations[which];
	sm_simulation_state* baseline = sm_simulation_state_deserialize(f->baseline, f->baseline_size, &err);
	if (baseline == NULL || sm_simulation_restore_state(sim, baseline) != SM_OK)
		fail("the baseline state does not restore", err.message);
	sm_simulation_state_destroy(baseline);
	observed before = observe(sim);
	const sm_status restored = sm_simulation_restore_state(sim, state);
	observed after = observe(sim);
	if (restored != SM_OK) {
		if (sm_simulation_last_error(sim)[0] == '\0')
			fail("restore refused a state without saying why", NULL);
		if (!same(&before, &after))
			fail("a refused restore changed the simulation", sm_simulation_last_error(sim));
	} else {
		// Restored, the simulation saves the snapshot it was given (its padding aside: compare
		// up to the break events, then each event's fields).
		const int32_t breaks = sm_simulation_break_count(sim);
		const size_t events = (size_t)breaks * sizeof(sm_break_event);
		if (after.size != n || HEADER_BYTES + events + CHECKSUM_BYTES > n ||
		    memcmp(after.state, bytes, RESERVED_OFFSET) != 0 ||
		    memcmp(after.state + RESERVED_END, bytes + RESERVED_END,
		           n - RESERVED_END - events - CHECKSUM_BYTES) != 0)
			fail("a restored state saves other bytes", NULL);
		for (int32_t b = 0; b < breaks; b++) {
			sm_break_event e;
			memcpy(&e, bytes + n - CHECKSUM_BYTES - events + (size_t)b * sizeof e, sizeof e);
			const sm_break_event held = sm_simulation_break(sim, b);
			if (memcmp(&e.time, &held.time, sizeof e.time) != 0 || e.spring != held.spring ||
			    sm_model_spring_enabled(sm_simulation_model(sim), e.spring))
				fail("a restored state holds other break events", NULL);
		}
		const double t0 = sm_simulation_time(sim), t_end = t0 + ADVANCE;
		const sm_status advanced = control & CONTROL_INTERPOLATED
		                               ? sm_simulation_advance_interpolated(sim, t_end, t0 + 2.0 * ADVANCE)
		                               : sm_simulation_advance(sim, t_end);
		const double t = sm_simulation_time(sim);
		if (advanced == SM_OK) {
			if (t != t_end || !finite_motion(sim) || !isfinite(sm_simulation_dissipated_energy(sim)))
				fail("an advance from a restored state succeeded with a state not finite", NULL);
		} else if (sm_simulation_last_error(sim)[0] == '\0' || !(t >= t0 && t <= t_end)) {
			fail("an advance from a restored state failed without saying why, or left its interval",
			     sm_simulation_last_error(sim));
		}
	}
	// Whatever the input did, the simulation restored to the baseline again advances as it did
	// before any input, bit for bit.
	baseline = sm_simulation_state_deserialize(f->baseline, f->baseline_size, &err);
	if (baseline == NULL || sm_simulation_restore_state(sim, baseline) != SM_OK ||
	    sm_simulation_advance(sim, sm_simulation_time(sim) + ADVANCE) != SM_OK)
		fail("the baseline state does not restore and advance after an input", sm_simulation_last_error(sim));
	sm_simulation_state_destroy(baseline);
	const double dissipated = sm_simulation_dissipated_energy(sim);
	if (memcmp(sm_simulation_positions(sim), f->reference_position[which],
	           sizeof f->reference_position[which]) != 0 ||
	    memcmp(sm_simulation_velocities(sim), f->reference_velocity[which],
	           sizeof f->reference_velocity[which]) != 0 ||
	    memcmp(&dissipated, &f->reference_dissipated[which], sizeof dissipated) != 0)
		fail("after an input, the baseline state advances otherwise than before any", NULL);
	free(after.state);
	free(before.state);
	sm_simulation_state_destroy(state);
	free(bytes);
	return 0;
}

// Snapshots of a simulation's state: save and restore, and their serialised form.
//
// A snapshot holds what the next advance depends on beyond the model: the time, CVODE's state
// vector (free positions and velocities, dissipated energy, inputs' work), the inputs (external forces and
// their ramps, the driven particles' motions) and the break events. It is tied to a model's topology by a
// hash, and restoring one restarts CVODE from it.
#include "model_internal.h"
#include "simulation_internal.h"

#include <nvector/nvector_serial.h>

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

// A snapshot in one allocation: the header, then its arrays (doubles first, for alignment). The
// springs it holds broken are those of its break events; which springs the model itself disables
// is the simulation's, not the snapshot's.
struct sm_simulation_state {
	uint64_t topology;  // sm_simulation_topology_hash of the model it was taken from
	int32_t particle_count, spring_count, free_count, break_count;
	double time;                 // [s]
	double* y;                   // CVODE's state: free x, free v, dissipated energy, inputs' work
	double* external_force;      // 3 per particle [N]
	double* force_rate;          // 3 per particle [N/s]
	double* force_time;          // per particle [s]
	double* drive_position;      // 3 per particle [m]
	double* drive_velocity;      // [m/s]
	double* drive_acceleration;  // [m/s^2]
	double* drive_time;          // per particle [s]
	sm_break_event* breaks;      // break_count
};

// 64-bit FNV-1a: the hash h (FNV_OFFSET to start) extended by `length` bytes.
#define FNV_OFFSET 14695981039346656037ull
static uint64_t fnv1a(uint64_t h, const void* bytes, size_t length)
{
	const unsigned char* b = bytes;
	for (size_t k = 0; k < length; k++)
		h = (h ^ b[k]) * 1099511628211ull;
	return h;
}

uint64_t sm_simulation_topology_hash(const sm_model* m)
{
	const int32_t head[2] = {m->particle_count, m->spring_count};
	uint64_t h = fnv1a(FNV_OFFSET, head, sizeof head);
	for (int32_t i = 0; i < m->particle_count; i++) {
		const int32_t motion = (int32_t)m->motion[i];
		h = fnv1a(h, &motion, sizeof motion);
	}
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t spring[3] = {m->spring_a[s], m->spring_b[s], m->zero_length[s] ? 1 : 0};
		h = fnv1a(h, spring, sizeof spring);
	}
	return h;
}

// Doubles per particle of a snapshot: the force, its rate and time, the driven motion and its time.
#define PARTICLE_DOUBLES 17

// Bytes of a snapshot's arrays: y (6 free + SM_ENERGY_COMPONENTS), PARTICLE_DOUBLES per particle,
// the break events.
static size_t state_payload(int64_t particles, int64_t free, int64_t breaks)
{
	return (size_t)(6 * free + SM_ENERGY_COMPONENTS + PARTICLE_DOUBLES * particles) * sizeof(double) +
	       (size_t)breaks * sizeof(sm_break_event);
}

// A snapshot of the given counts, its arrays laid out after the header (contents unset).
static sm_simulation_state* allocate_state(int32_t particles, int32_t springs, int32_t free, int32_t breaks)
{
	sm_simulation_state* s = malloc(sizeof(sm_simulation_state) + state_payload(particles, free, breaks));
	if (s == NULL)
		return NULL;
	const size_t n = (size_t)particles;
	s->particle_count = particles;
	s->spring_count = springs;
	s->free_count = free;
	s->break_count = breaks;
	s->y = (double*)(s + 1);
	s->external_force = s->y + 6 * (size_t)free + SM_ENERGY_COMPONENTS;
	s->force_rate = s->external_force + 3 * n;
	s->force_time = s->force_rate + 3 * n;
	s->drive_position = s->force_time + n;
	s->drive_velocity = s->drive_position + 3 * n;
	s->drive_acceleration = s->drive_velocity + 3 * n;
	s->drive_time = s->drive_acceleration + 3 * n;
	s->breaks = (sm_break_event*)(s->drive_time + n);
	return s;
}

sm_simulation_state* sm_simulation_save_state(const sm_simulation* sim)
{
	if (sim == NULL)
		return NULL;
	const size_t n = (size_t)sim->particle_count, ny = (size_t)sm_simulation_state_length(sim);
	sm_simulation_state* s =
	    allocate_state(sim->particle_count, sim->spring_count, sim->free_count, sim->break_count);
	if (s == NULL)
		return NULL;
	s->topology = sim->topology;
	s->time = sim->time;
	memcpy(s->y, N_VGetArrayPointer(sim->y), ny * sizeof(double));
	// The inputs' work itself, not CVODE's part of it, which is less the driven particles' kinetic
	// energy: a simulation whose driven particles have other masses restores the work saved. Where
	// that energy overflows (and the work reads infinite) CVODE's part holds none of it
	// (sm_simulation_start_input_work), and the finite rest is saved: bytes that read back.
	const double work = sm_simulation_input_work(sim);
	s->y[sm_simulation_work_index(sim)] =
	    isfinite(work) ? work : s->y[sm_simulation_work_index(sim)] + sim->jump_work;
	memcpy(s->external_force, sim->external_force, 3 * n * sizeof(double));
	memcpy(s->force_rate, sim->force_rate, 3 * n * sizeof(double));
	memcpy(s->force_time, sim->force_time, n * sizeof(double));
	memcpy(s->drive_position, sim->drive_position, 3 * n * sizeof(double));
	memcpy(s->drive_velocity, sim->drive_velocity, 3 * n * sizeof(double));
	memcpy(s->drive_acceleration, sim->drive_acceleration, 3 * n * sizeof(double));
	memcpy(s->drive_time, sim->drive_time, n * sizeof(double));
	// Field by field into zeroed memory, so that the events' padding is zero in serialised bytes.
	memset(s->breaks, 0, (size_t)sim->break_count * sizeof(sm_break_event));
	for (int32_t b = 0; b < sim->break_count; b++) {
		s->breaks[b].time = sim->breaks[b].time;
		s->breaks[b].spring = sim->breaks[b].spring;
	}
	return s;
}

sm_status sm_simulation_restore_state(sm_simulation* sim, const sm_simulation_state* s)
{
	if (sim == NULL || s == NULL)
		return sim ? sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT, "restore_state: no state")
		           : SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	// The counts too: the hash is a field of the snapshot, which bytes read back may hold beside
	// other counts, and the arrays copied below have the simulation's sizes.
	if (s->topology != sim->topology || s->particle_count != sim->particle_count ||
	    s->spring_count != sim->spring_count || s->free_count != sim->free_count)
		return sm_simulation_fail(
		    sim, SM_ERROR_TOPOLOGY,
		    "restore_state: the state is of a model of %d particles (%d free) and %d springs, the "
		    "simulation's has %d (%d free) and %d, or its particles move otherwise or its springs join "
		    "other particles",
		    (int)s->particle_count, (int)s->free_count, (int)s->spring_count, (int)sim->particle_count,
		    (int)sim->free_count, (int)sim->spring_count);
	const int32_t overflowing = sm_simulation_overflowing_driven_particle(
	    sim, s->time, s->drive_position, s->drive_velocity, s->drive_acceleration, s->drive_time);
	if (overflowing >= 0) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(s->time, t);
		return sm_simulation_fail(
		    sim, SM_ERROR_NOT_FINITE,
		    "restore_state: driven particle %d's position at the state's time t = %s s is not finite",
		    (int)overflowing, t);
	}
	const int32_t pushed =
	    sm_simulation_overflowing_force(sim, s->time, s->external_force, s->force_rate, s->force_time);
	if (pushed >= 0) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(s->time, t);
		return sm_simulation_fail(
		    sim, SM_ERROR_NOT_FINITE,
		    "restore_state: particle %d's external force at the state's time t = %s s is not finite (its ramp)",
		    (int)pushed, t);
	}
	if (s->break_count > sim->break_capacity) {
		sm_break_event* b = realloc(sim->breaks, (size_t)s->break_count * sizeof *b);
		if (b == NULL)
			return sm_simulation_fail(sim, SM_ERROR_OUT_OF_MEMORY,
			                          "restore_state: out of memory for the break events");
		sim->breaks = b;
		sim->break_capacity = s->break_count;
	}
	const size_t n = (size_t)sim->particle_count;
	sim->time = s->time;
	memcpy(N_VGetArrayPointer(sim->y), s->y, (size_t)sm_simulation_state_length(sim) * sizeof(double));
	memcpy(sim->external_force, s->external_force, 3 * n * sizeof(double));
	memcpy(sim->force_rate, s->force_rate, 3 * n * sizeof(double));
	memcpy(sim->force_time, s->force_time, n * sizeof(double));
	memcpy(sim->drive_position, s->drive_position, 3 * n * sizeof(double));
	memcpy(sim->drive_velocity, s->drive_velocity, 3 * n * sizeof(double));
	memcpy(sim->drive_acceleration, s->drive_acceleration, 3 * n * sizeof(double));
	memcpy(sim->drive_time, s->drive_time, n * sizeof(double));
	sim->ramping_forces = sim->forced_particles = 0;
	for (size_t k = 0; k < n; k++) {
		const double* r = sim->force_rate + 3 * k;
		const double* f = sim->external_force + 3 * k;
		const bool ramps = r[0] != 0.0 || r[1] != 0.0 || r[2] != 0.0;
		sim->ramping_forces += ramps;
		sim->forced_particles +=
		    sim->model->motion[k] == SM_PARTICLE_FREE && (ramps || f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0);
	}
	if (s->break_count > 0)
		memcpy(sim->breaks, s->breaks, (size_t)s->break_count * sizeof(sm_break_event));
	sim->break_count = s->break_count;
	// Enabled: what the simulation's model enables, less the springs that had broken at the save.
	sm_simulation_restore_springs(sim);
	for (int32_t b = 0; b < s->break_count; b++)
		sm_model_set_spring_enabled(sim->model, s->breaks[b].spring, false);
	sim->time_origin = sim->time;  // CVODE's axis of the restart due, as set_state does
	sim->need_restart = true;
	sim->forget_factor = true;
	sim->input_changed = false;
	sim->jumps = (sm_input_jumps){0.0, 0.0, 0.0};
	sm_input_origins_forget(sim);
	sm_simulation_refresh_outputs(sim);
	sm_simulation_start_input_work(sim, s->y[sm_simulation_work_index(sim)]);  // as saved, to the bit
	return SM_OK;
}

void sm_simulation_state_destroy(sm_simulation_state* state)
{
	free(state);
}

// The serialised form: a header of fixed layout, the arrays as the snapshot holds them, and a
// 64-bit FNV-1a checksum of everything before it. Numbers in the machine's own byte order.
typedef struct serialized_header {
	char magic[8];  // "smstate", NUL-terminated
	uint32_t layout;
	int32_t particle_count, spring_count, free_count, break_count;
	int32_t reserved;  // 0
	uint64_t topology;
	double time;  // [s]
} serialized_header;

#define STATE_LAYOUT 3u  // 2: force ramps and driven accelerations; 3: the inputs' work

size_t sm_simulation_state_size(const sm_simulation_state* s)
{
	if (s == NULL)
		return 0;
	return sizeof(serialized_header) + state_payload(s->particle_count, s->free_count, s->break_count) +
	       sizeof(uint64_t);
}

sm_status sm_simulation_state_serialize(const sm_simulation_state* s, void* buffer, size_t size)
{
	if (s == NULL || buffer == NULL || size < sm_simulation_state_size(s))
		return SM_ERROR_INVALID_ARGUMENT;
	serialized_header h;
	memset(&h, 0, sizeof h);
	memcpy(h.magic, "smstate", 8);
	h.layout = STATE_LAYOUT;
	h.particle_count = s->particle_count;
	h.spring_count = s->spring_count;
	h.free_count = s->free_count;
	h.break_count = s->break_count;
	h.topology = s->topology;
	h.time = s->time;
	unsigned char* out = buffer;
	const size_t payload = state_payload(s->particle_count, s->free_count, s->break_count);
	memcpy(out, &h, sizeof h);
	memcpy(out + sizeof h, s->y, payload);  // the arrays lie one after another from y on
	const uint64_t sum = fnv1a(FNV_OFFSET, out, sizeof h + payload);
	memcpy(out + sizeof h + payload, &sum, sizeof sum);
	return SM_OK;
}

sm_simulation_state* sm_simulation_state_deserialize(const void* buffer, size_t size, sm_error* err)
{
	const unsigned char* in = buffer;
	serialized_header h;
	if (buffer == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "state_deserialize: buffer is NULL");
		return NULL;
	}
	if (size < sizeof h + sizeof(uint64_t)) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "state_deserialize: %zu bytes are no simulation state",
		             size);
		return NULL;
	}
	memcpy(&h, in, sizeof h);
	// The reserved field is zero in this layout; a later one may give it a meaning this one lacks.
	if (memcmp(h.magic, "smstate", 8) != 0 || h.layout != STATE_LAYOUT || h.reserved != 0) {
		sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "state_deserialize: not a simulation state of this springmass version (layout %u expected)",
		    STATE_LAYOUT);
		return NULL;
	}
	const bool counts = h.particle_count >= 0 && h.spring_count >= 0 && h.free_count >= 0 &&
	                    h.free_count <= h.particle_count && h.break_count >= 0 &&
	                    h.break_count <= h.spring_count;
	if (!counts ||
	    size != sizeof h + state_payload(h.particle_count, h.free_count, h.break_count) + sizeof(uint64_t)) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		             "state_deserialize: the state's counts and its %zu bytes disagree", size);
		return NULL;
	}
	const size_t payload = state_payload(h.particle_count, h.free_count, h.break_count);
	uint64_t sum;
	memcpy(&sum, in + sizeof h + payload, sizeof sum);
	if (sum != fnv1a(FNV_OFFSET, in, sizeof h + payload)) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		             "state_deserialize: checksum mismatch (a damaged state)");
		return NULL;
	}
	sm_simulation_state* s = allocate_state(h.particle_count, h.spring_count, h.free_count, h.break_count);
	if (s == NULL) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "state_deserialize: out of memory");
		return NULL;
	}
	s->topology = h.topology;
	s->time = h.time;
	memcpy(s->y, in + sizeof h, payload);
	bool valid = isfinite(s->time);
	const double* values = s->y;
	for (size_t k = 0; valid && k < (size_t)(6 * (int64_t)h.free_count + SM_ENERGY_COMPONENTS +
	                                         PARTICLE_DOUBLES * (int64_t)h.particle_count);
	     k++)
		valid = isfinite(values[k]);
	for (int32_t b = 0; valid && b < s->break_count; b++)
		valid =
		    s->breaks[b].spring >= 0 && s->breaks[b].spring < s->spring_count && isfinite(s->breaks[b].time);
	if (!valid) {
		free(s);
		sm_error_set(err, SM_ERROR_NOT_FINITE, "state_deserialize: the state holds a value out of range");
		return NULL;
	}
	// A spring breaks once: a state that lists one twice was not written by a simulation.
	if (s->break_count > 1) {
		unsigned char* broken = calloc((size_t)s->spring_count, 1);
		if (broken == NULL) {
			free(s);
			sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "state_deserialize: out of memory");
			return NULL;
		}
		int32_t twice = -1;
		for (int32_t b = 0; twice < 0 && b < s->break_count; b++) {
			if (broken[s->breaks[b].spring])
				twice = s->breaks[b].spring;
			broken[s->breaks[b].spring] = 1;
		}
		free(broken);
		if (twice >= 0) {
			free(s);
			sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
			             "state_deserialize: spring %d breaks twice in the state", (int)twice);
			return NULL;
		}
	}
	sm_error_clear(err);
	return s;
}

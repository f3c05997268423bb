// Input changes undone before the next advance (simulation_internal.h).
//
// A co-simulation master may set an input to a trial value, read an output that depends on it,
// and set the input back before it steps (probing, iterating at a communication point). Each set
// is a change for the simulation, which restarts CVODE at the next advance after a change; yet
// after the excursion the inputs are those of the last advance, and the run should be that of no
// excursion, to the bit. So the first change of a particle's input since the last advance records
// the input as it was (its path or ramp); an input set back onto that path is given those exact
// values again, and once every changed input is back, the flags the changes set (restart due,
// inputs changed, jump work) are put back as they were. An advance, a reset or a restore forgets
// the records: the inputs are then those of the new start. A new state, a model update or a cut
// keeps them, spanned: the restart it asks for stays, so an input set back after it is a change,
// yet onto the recorded path or ramp, to the bit, as in a run that never moved it (a ramp set
// anew from now, f0 + r t0 + r (t - t0), is f0 + r t only to round-off, and an iterative linear
// solver turns that last bit into differences within the tolerances).
#include "simulation_internal.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

void sm_input_origins_forget(sm_simulation* sim)
{
	for (int32_t k = 0; k < sim->origin_count; k++)
		sim->origin_slot[sim->origins[k].particle] = -1;
	sim->origin_count = 0;
	sim->origins_lost = false;
	sim->origins_spanned = false;
}

void sm_input_origins_span(sm_simulation* sim)
{
	sim->origins_spanned = sim->origin_count > 0;
}

const sm_input_origin* sm_input_origins_find(const sm_simulation* sim, int32_t particle)
{
	const int32_t k = sim->origin_slot[particle];
	return k >= 0 ? &sim->origins[k] : NULL;
}

void sm_input_origins_note(sm_simulation* sim, int32_t particle, bool driven)
{
	if (sim->origins_lost || sm_input_origins_find(sim, particle) != NULL)
		return;
	if (sim->origin_count == sim->origin_capacity) {
		// At most one origin per particle.
		int32_t capacity = sim->origin_capacity > 0 ? 2 * sim->origin_capacity : 8;
		if (capacity > sim->particle_count)
			capacity = sim->particle_count;
		sm_input_origin* grown =
		    capacity > sim->origin_count ? realloc(sim->origins, (size_t)capacity * sizeof *grown) : NULL;
		if (grown == NULL) {
			sim->origins_lost = true;  // no record: this change cannot count as undone
			return;
		}
		sim->origins = grown;
		sim->origin_capacity = capacity;
	}
	if (sim->origin_count == 0) {
		sim->flags_before.need_restart = sim->need_restart;
		sim->flags_before.input_jumped = sim->input_jumped;
		sim->flags_before.input_changed = sim->input_changed;
		sim->flags_before.jump_work = sim->jump_work;
		sim->flags_before.jumps = sim->jumps;
	}
	sm_input_origin* o = &sim->origins[sim->origin_count];
	const size_t p = 3 * (size_t)particle;
	o->particle = particle;
	if (driven) {
		memcpy(o->value, sim->drive_position + p, sizeof o->value);
		memcpy(o->rate, sim->drive_velocity + p, sizeof o->rate);
		memcpy(o->acceleration, sim->drive_acceleration + p, sizeof o->acceleration);
		o->time = sim->drive_time[particle];
	} else {
		memcpy(o->value, sim->external_force + p, sizeof o->value);
		memcpy(o->rate, sim->force_rate + p, sizeof o->rate);
		memset(o->acceleration, 0, sizeof o->acceleration);
		o->time = sim->force_time[particle];
	}
	sim->origin_slot[particle] = sim->origin_count++;
}

bool sm_input_origins_settle(sm_simulation* sim, int32_t particle)
{
	const int32_t k = sim->origin_slot[particle];
	const int32_t last = --sim->origin_count;
	if (k != last) {
		sim->origins[k] = sim->origins[last];
		sim->origin_slot[sim->origins[k].particle] = k;
	}
	sim->origin_slot[particle] = -1;
	if (sim->origin_count > 0 || sim->origins_lost)
		return false;
	if (sim->origins_spanned) {
		sim->origins_spanned = false;  // the next input changed starts records of its own
		return false;
	}
	sim->need_restart = sim->flags_before.need_restart;
	sim->input_jumped = sim->flags_before.input_jumped;
	sim->input_changed = sim->flags_before.input_changed;
	sim->jump_work = sim->flags_before.jump_work;
	sim->jumps = sim->flags_before.jumps;
	return true;
}

// The chunks of the reduced solver's parallel loops (pcg, large models) and what follows from
// them: the springs in chunk order, with the model's constants copied into that order, and the
// forces and Jacobian records evaluated chunk by chunk.
//
// Why chunks. A spring writes to both its particles, so two threads may run springs at once only
// if no particle is written by both. The particles are cut into PARALLEL_CHUNKS contiguous ranges;
// the springs with both ends in one range belong to its chunk, and the few between ranges
// (particles numbered along the structure, as structures and meshes number them) are run after
// the chunks on the caller's thread. Every loop over particles or springs runs chunk by chunk,
// and every sum adds the chunks' partial sums in chunk order: the chunks depend on the model
// alone, so the results do not depend on the number of threads, bit for bit.
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include <stdlib.h>

typedef struct forces_job {
	sm_reduced* r;
	const double *x, *v, *f_external;
	double* f;
	sm_spring_order order;
} forces_job;

// Chunk c of the forces: its particles' body forces, then its springs, with their records.
static void forces_chunk(void* context, int c)
{
	const forces_job* j = context;
	sm_reduced* r = j->r;
	const double body = sm_model_body_forces_range(r->sim->model, j->v, j->f_external, j->f,
	                                               r->chunk_particle[c], r->chunk_particle[c + 1]);
	r->partial[c] =
	    sm_spring_order_forces_and_jacobians(&j->order, r->chunk_spring[c], r->chunk_spring[c + 1], j->x,
		                                     j->v, j->f, r->springs->data) +
	    body;
}

// sm_model_forces_power_and_jacobians at x, v into f and the solver's records, chunk by chunk
// (the springs between chunks after, on the caller's thread, and the chunks' powers added in
// chunk order) when the model is split into chunks; returns the dissipated power [W].
double sm_reduced_forces_and_records(sm_reduced* r, const double* x, const double* v,
                                     const double* f_external, double* f)
{
	const sm_model* m = r->sim->model;
	if (r->slot == NULL)
		return sm_model_forces_power_and_jacobians(m, x, v, f_external, f, r->springs);
	forces_job job = {
	    r, x,
	    v, f_external,
	    f, {r->ordered_a, r->ordered_b, r->ordered_rest_length, r->ordered_stiffness, r->ordered_damping}};
	sm_workers_run(r->workers, forces_chunk, &job, r->chunks);
	const double boundary = sm_spring_order_forces_and_jacobians(&job.order, r->chunk_spring[r->chunks],
	                                                             m->spring_count, x, v, f, r->springs->data);
	r->springs->variant = SM_JACOBIAN_DEFINITE;
	r->springs->evaluated = 1;
	return sm_reduced_sum_partials(r) + boundary;
}

// The springs' entries (entry_a, entry_b) and, in chunks, the model's spring constants in chunk
// order: when the chunks are built and at every invalidation, which follows every change of them (a
// break, a restore, a reset, a new model).
void sm_reduced_load_spring_order(sm_reduced* r)
{
	const sm_model* m = r->sim->model;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t k = r->slot != NULL ? r->slot[s] : s;
		r->entry_a[k] = 3 * m->spring_a[s];
		r->entry_b[k] = 3 * m->spring_b[s];
		if (r->slot == NULL)
			continue;
		r->ordered_rest_length[k] = m->rest_length[s];
		r->ordered_stiffness[k] = m->stiffness[s];
		r->ordered_damping[k] = m->damping[s];
	}
}

// The chunks of the parallel loops (see sm_reduced): one, or PARALLEL_CHUNKS of equal particle
// counts for pcg from min_particles free particles on, when at most max_boundary_fraction of the
// springs join two chunks; the aggregates' member lists; and the team of sm_simulation_def.threads
// threads, at most one per chunk and per processor the process may run on (none if it cannot be
// had: the chunks then run in turn, with the same results). Returns false on out of memory.
bool sm_reduced_build_chunks(sm_reduced* r, int32_t min_particles, double max_boundary_fraction)
{
	const sm_model* m = r->sim->model;
	const int32_t np = m->particle_count, ns = m->spring_count;
	r->chunks = 1;
	r->chunk_particle[0] = 0, r->chunk_particle[1] = np;
	r->chunk_spring[0] = 0, r->chunk_spring[1] = ns;
	r->chunk_aggregate[0] = 0, r->chunk_aggregate[1] = r->aggregate_count;
	r->entry_a = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->entry_b = malloc(((size_t)ns + 1) * sizeof(int32_t));
	if (!r->entry_a || !r->entry_b)
		return false;
	if (r->two_level) {
		// Each aggregate's members in increasing order, by a counting sort: counts at I + 2, their
		// running sums at I + 2 (the start of I + 1), then each member placed at member_first[I + 1],
		// which it advances: at the end member_first[I + 1] is the end of I, the start of I + 1.
		r->member_first = calloc((size_t)r->aggregate_count + 2, sizeof(int32_t));
		r->member = malloc(((size_t)np + 1) * sizeof(int32_t));
		if (!r->member_first || !r->member)
			return false;
		for (int32_t i = 0; i < np; i++)
			if (r->aggregate[i] >= 0)
				r->member_first[r->aggregate[i] + 2]++;
		for (int32_t I = 0; I < r->aggregate_count; I++)
			r->member_first[I + 2] += r->member_first[I + 1];
		for (int32_t i = 0; i < np; i++)
			if (r->aggregate[i] >= 0)
				r->member[r->member_first[r->aggregate[i] + 1]++] = i;
	}
	sm_reduced_load_spring_order(r);
	if (r->use_cholmod || r->sim->free_count < min_particles)
		return true;
	const int chunks = PARALLEL_CHUNKS;
	int32_t* key = malloc(((size_t)ns + 1) * sizeof(int32_t));
	if (key == NULL)
		return false;
	int32_t count[PARALLEL_CHUNKS + 2] = {0};
	for (int c = 0; c <= chunks; c++)
		r->chunk_particle[c] = (int32_t)((int64_t)np * c / chunks);
	for (int32_t s = 0; s < ns; s++) {
		const int32_t a = m->spring_a[s], b = m->spring_b[s];
		int ca = 0, cb = 0;
		while (a >= r->chunk_particle[ca + 1])
			ca++;
		while (b >= r->chunk_particle[cb + 1])
			cb++;
		key[s] = ca == cb ? ca : chunks;
		count[key[s] + 1]++;
	}
	if (count[chunks + 1] > max_boundary_fraction * ns) {
		// Too many springs between chunks, which run on one thread: one chunk after all.
		free(key);
		r->chunk_particle[1] = np;
		return true;  // the entries as loaded above, in the model's order
	}
	r->slot = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_a = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_b = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_rest_length = malloc(((size_t)ns + 1) * sizeof(double));
	r->ordered_stiffness = malloc(((size_t)ns + 1) * sizeof(double));
	r->ordered_damping = malloc(((size_t)ns + 1) * sizeof(double));
	if (!r->slot || !r->ordered_a || !r->ordered_b || !r->ordered_rest_length || !r->ordered_stiffness ||
	    !r->ordered_damping) {
		free(key);
		return false;
	}
	for (int c = 0; c <= chunks; c++)
		count[c + 1] += count[c];
	for (int c = 0; c <= chunks; c++)
		r->chunk_spring[c] = count[c];
	for (int32_t s = 0; s < ns; s++) {
		const int32_t k = count[key[s]]++;
		r->slot[s] = k;
		r->ordered_a[k] = m->spring_a[s];
		r->ordered_b[k] = m->spring_b[s];
	}
	free(key);
	sm_reduced_load_spring_order(r);
	// The restriction writes each aggregate's own entries only: any split of them will do.
	for (int c = 0; c <= chunks; c++)
		r->chunk_aggregate[c] = (int32_t)((int64_t)r->aggregate_count * c / chunks);
	r->chunks = chunks;
	// More threads than processors would only wait for each other.
	int threads = r->sim->def.threads < chunks ? r->sim->def.threads : chunks;
	const int processors = sm_workers_processors();
	if (threads > processors)
		threads = processors;
	r->workers = sm_workers_create(threads);
	return true;
}

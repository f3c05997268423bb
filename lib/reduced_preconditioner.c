// The pcg variant's preconditioner: block Jacobi, and from TWO_LEVEL_MIN_PARTICLES free particles
// on (linear_solver_reduced.c) a coarse correction over aggregates of neighbouring particles
// (reduced_aggregates.c builds them); its preparation at each gamma and its application.
//
// Derivation. Each spring's share of A is (reduced_products.c)
//   B = gamma^2 K + gamma D = gamma^2 beta I + u w^T,  w = gamma^2 z + gamma kd u
// (the factored records, forces.c) at its ends' diagonal blocks; A's diagonal block at a free
// particle i is therefore
//   A_ii = m_i (1 + gamma alpha) I + sum of B over its springs,
// inverted for block Jacobi. The two-level preconditioner adds a coarse correction:
//   B_2 = A_d^-1 + P A_c^-1 P^T,  A_c = P^T A P,
// A_d the block diagonal of A, P the prolongation that moves each aggregate as one body (P^T sums an
// aggregate's members, P copies an aggregate's value to its members). Both terms are symmetric,
// the first positive definite and the second semi-definite, so B_2 is symmetric positive definite
// and conjugate gradients apply. Block Jacobi smooths the short waves; the coarse correction takes
// the long ones, whose slow convergence made the iterations grow with the model's size.
//
// The Galerkin coarse matrix A_c sums A's rows and columns over each aggregate: a spring between
// aggregates I != J adds B to the coarse blocks (I, I) and (J, J) and subtracts it from (I, J) and
// (J, I); a spring to a constrained particle adds it to its free end's (I, I); one inside an
// aggregate adds nothing (+B and -B cancel). P^T M P is the aggregates' masses on the diagonal,
// so A_c = M_c (1 + gamma alpha) + those sums. It is factorised by CHOLMOD (about a tenth of the
// unknowns on the cloth; in two halves whose triangular solves run at once for a model in chunks,
// coarse_halves.h), or from MULTILEVEL_MIN_PARTICLES on solved approximately by a few conjugate-
// gradient iterations preconditioned by a multilevel V-cycle (preconditioner_multilevel.c), the
// exact solve having grown faster than the model; the preconditioner is then no longer a fixed
// linear map and the outer conjugate gradients are flexible (reduced_conjugate_gradients.c).
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include "cholmod_factorize.h"

#include <math.h>
#include <string.h>

#if defined(SM_REDUCED_SSE2)
#include <emmintrin.h>
#endif

// The coarse matrix is summed and factorised again after COARSE_MAX_AGE preconditioner
// preparations (a preparation follows every Jacobian evaluation and change of gamma) or when gamma
// has changed by more than COARSE_GAMMA_CHANGE (relative) since; in between the older factor
// serves (the preconditioner stays symmetric positive definite, only its quality varies).
// Measured on the benchmark cloth n = 64 over 0.2 s: a factorisation at every preparation took 17%
// of the run in CHOLMOD; with (10, 0.3) the iterations rose by 1% (8419 to 8523) and the run took
// 0.65 times as long; (50, 0.5) cost 18% more iterations, no refresh at all 3.3 times as many.
#define COARSE_MAX_AGE 10
#define COARSE_GAMMA_CHANGE 0.3

// Conjugate-gradient iterations of the multilevel coarse solve (measurements with
// MULTILEVEL_MIN_PARTICLES, linear_solver_reduced.c).
#define COARSE_ITERATIONS 3

// Adds sign B (row-major 3x3) to the coarse block whose first entry is `entry`, in block row I.
static void coarse_add(double* values, const sm_reduced* r, int32_t I, int64_t entry, const double* B,
                       double sign)
{
	const int64_t stride = 3 * (r->coarse_first[I + 1] - r->coarse_first[I]);
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			values[entry + stride * i + j] += sign * B[3 * i + j];
}

typedef struct preconditioner_job {
	sm_reduced* r;
	double gamma;
	bool singular[PARALLEL_CHUNKS];
} preconditioner_job;

// The diagonal blocks' sums (after the inverses' storage in block_inverse, 9 per particle).
static double* block_sums(const sm_reduced* r)
{
	return r->block_inverse + 9 * (size_t)r->sim->model->particle_count;
}

// The springs at positions begin .. end of the chunk order: their scaled records (u, w,
// gamma^2 beta) from the Jacobian's (q: u = q[0 .. 2], z = q[3 .. 5], beta = q[6], kd = q[7]),
// and B added to the diagonal sums of both ends. Consecutive springs often share their first
// particle (structures list their springs particle by particle): its sum is held in registers
// from its first spring to its last, loaded before and stored after. No other spring of the run
// reaches it (a spring's ends differ), so the additions are those of adding to memory, in the
// same order: the same bits, without waiting for each stored sum to be loaded again.
static void add_spring_shares(sm_reduced* r, double gamma, int32_t begin, int32_t end)
{
	const int32_t* restrict first = r->entry_a;
	const int32_t* restrict second = r->entry_b;
	const double* restrict data = r->springs->data;
	double* restrict scaled = r->scaled;
	// gamma and gamma^2 times the solve's scale (the same numbers at scale 1)
	const double g1 = sm_reduced_scale(gamma) * gamma, g2 = g1 * gamma;
	double* restrict diag = block_sums(r);
	if (begin >= end)
		return;
	int32_t held = first[begin];
#if defined(SM_REDUCED_SSE2)
	// Pairs of entries in the two lanes of SSE2 registers (part of every x86-64 processor): w_x and
	// w_y, and B and the sums as (B_0, B_1), (B_2, B_3), (B_4, B_5), (B_6, B_7), B_8, with (d, 0) for
	// the d of B_0 and B_4 (B_1 + 0 and B_5 + 0 differ from B_1, B_5 at most in the sign of a zero,
	// which a sum that starts at +0 does not keep). Each lane does the scalar operations in their
	// order: the same bits.
	__m128d h[4];
	double h8;
	const double* sum_held = diag + 3 * (size_t)held;
	for (int i = 0; i < 4; i++)
		h[i] = _mm_loadu_pd(sum_held + 2 * i);
	h8 = sum_held[8];
	const __m128d g2v = _mm_set1_pd(g2);
	for (int32_t k = begin; k < end; k++) {
		const double* restrict q = data + SPRING_JACOBIAN_STRIDE * (size_t)k;
		const int32_t a = first[k];
		if (a != held) {
			double* out = diag + 3 * (size_t)held;
			for (int i = 0; i < 4; i++)
				_mm_storeu_pd(out + 2 * i, h[i]);
			out[8] = h8;
			held = a;
			const double* in = diag + 3 * (size_t)held;
			for (int i = 0; i < 4; i++)
				h[i] = _mm_loadu_pd(in + 2 * i);
			h8 = in[8];
		}
		const double gk = g1 * q[7];
		const __m128d u01 = _mm_loadu_pd(q);
		const __m128d w01 =
		    _mm_add_pd(_mm_mul_pd(g2v, _mm_loadu_pd(q + 3)), _mm_mul_pd(_mm_set1_pd(gk), u01));
		const double w2 = g2 * q[5] + gk * q[2];
		const double d = g2 * q[6];
		double* restrict record = scaled + SCALED_STRIDE * (size_t)k;
		_mm_storeu_pd(record, u01);
		record[2] = q[2];
		_mm_storeu_pd(record + 3, w01);
		record[5] = w2;
		record[6] = d;
		const __m128d dv = _mm_set_sd(d);
		const __m128d w2v = _mm_set_sd(w2);
		const __m128d B[4] = {
		    _mm_add_pd(_mm_mul_pd(_mm_set1_pd(q[0]), w01), dv),
		    _mm_mul_pd(u01, _mm_unpacklo_pd(w2v, w01)),
		    _mm_add_pd(_mm_mul_pd(_mm_set1_pd(q[1]), _mm_shuffle_pd(w01, w2v, 1)), dv),
		    _mm_mul_pd(_mm_set1_pd(q[2]), w01),
		};
		const double B8 = q[2] * w2 + d;
		double* restrict sum = diag + 3 * (size_t)second[k];
		for (int i = 0; i < 4; i++) {
			h[i] = _mm_add_pd(h[i], B[i]);
			_mm_storeu_pd(sum + 2 * i, _mm_add_pd(_mm_loadu_pd(sum + 2 * i), B[i]));
		}
		h8 += B8;
		sum[8] += B8;
	}
	double* out = diag + 3 * (size_t)held;
	for (int i = 0; i < 4; i++)
		_mm_storeu_pd(out + 2 * i, h[i]);
	out[8] = h8;
#else
	double h[9];
	memcpy(h, diag + 3 * (size_t)held, sizeof h);
	for (int32_t k = begin; k < end; k++) {
		const double* restrict q = data + SPRING_JACOBIAN_STRIDE * (size_t)k;
		const int32_t a = first[k];
		if (a != held) {
			memcpy(diag + 3 * (size_t)held, h, sizeof h);
			held = a;
			memcpy(h, diag + 3 * (size_t)held, sizeof h);
		}
		const double w[3] = {g2 * q[3] + g1 * q[7] * q[0], g2 * q[4] + g1 * q[7] * q[1],
		                     g2 * q[5] + g1 * q[7] * q[2]};
		const double d = g2 * q[6];
		double* restrict record = scaled + SCALED_STRIDE * (size_t)k;
		record[0] = q[0], record[1] = q[1], record[2] = q[2];
		record[3] = w[0], record[4] = w[1], record[5] = w[2];
		record[6] = d;
		const double B[9] = {q[0] * w[0] + d, q[0] * w[1], q[0] * w[2], q[1] * w[0],    q[1] * w[1] + d,
		                     q[1] * w[2],     q[2] * w[0], q[2] * w[1], q[2] * w[2] + d};
		double* restrict sum = diag + 3 * (size_t)second[k];
		for (int i = 0; i < 9; i++) {
			h[i] += B[i];
			sum[i] += B[i];
		}
	}
	memcpy(diag + 3 * (size_t)held, h, sizeof h);
#endif
}

// Chunk c: its particles' diagonal sums cleared, then its springs' shares added (they reach no
// other chunk's particles).
static void spring_shares_chunk(void* context, int c)
{
	preconditioner_job* j = context;
	sm_reduced* r = j->r;
	double* diag = block_sums(r);
	memset(diag + 9 * (size_t)r->chunk_particle[c], 0,
	       9 * (size_t)(r->chunk_particle[c + 1] - r->chunk_particle[c]) * sizeof(double));
	add_spring_shares(r, j->gamma, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

// Chunk c: the mass term added to its free particles' diagonal blocks, which are inverted.
static void invert_chunk(void* context, int c)
{
	preconditioner_job* j = context;
	sm_reduced* r = j->r;
	const sm_model* m = r->sim->model;
	const double scale = sm_reduced_scale(j->gamma);
	const double damping = scale + scale * j->gamma * m->def.mass_damping;
	double* diag = block_sums(r);
	j->singular[c] = false;
	for (int32_t i = r->chunk_particle[c]; i < r->chunk_particle[c + 1]; i++) {
		double* inv = r->block_inverse + 9 * (size_t)i;
		if (m->free_index[i] < 0) {
			memset(inv, 0, 9 * sizeof(double));
			continue;
		}
		double* a = diag + 9 * (size_t)i;
		const double mass = m->mass[i] * damping;
		a[0] += mass, a[4] += mass, a[8] += mass;
		double t[9];
		// Inverted (t written) even after a singular block, so that no entry is copied unset.
		if (!sm_invert3(a, t))
			j->singular[c] = true;
		// Stored by column pairs for block Jacobi: (t00, t10), (t01, t11), (t02, t12), then the
		// last row t20, t21, t22.
		inv[0] = t[0], inv[1] = t[3], inv[2] = t[1], inv[3] = t[4], inv[4] = t[2], inv[5] = t[5];
		inv[6] = t[6], inv[7] = t[7], inv[8] = t[8];
	}
}

// The coarse matrix at gamma from the scaled records (B = u w^T + gamma^2 beta I, the numbers
// add_spring_shares summed), the springs in the model's order; then factorised. Returns 0, 1 if
// it is not positive definite, -1 if out of memory (no symbolic analysis could be made).
static int refresh_coarse(sm_reduced* r, double gamma)
{
	const sm_model* m = r->sim->model;
	const double scale = sm_reduced_scale(gamma);
	const double damping = scale + scale * gamma * m->def.mass_damping;
	double* coarse = r->coarse->x;
	memset(coarse, 0, 9 * (size_t)r->coarse_first[r->aggregate_count] * sizeof(double));
	r->coarse_gamma = gamma;
	r->coarse_scale = scale;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int64_t* entry = r->spring_coarse + 4 * (size_t)s;
		if (entry[0] < 0 && entry[1] < 0)
			continue;
		const double* e = r->scaled + SCALED_STRIDE * (size_t)(r->slot != NULL ? r->slot[s] : s);
		const double B[9] = {e[0] * e[3] + e[6], e[0] * e[4],        e[0] * e[5],
		                     e[1] * e[3],        e[1] * e[4] + e[6], e[1] * e[5],
		                     e[2] * e[3],        e[2] * e[4],        e[2] * e[5] + e[6]};
		const int32_t I = r->aggregate[m->spring_a[s]], J = r->aggregate[m->spring_b[s]];
		if (entry[0] >= 0)
			coarse_add(coarse, r, I, entry[0], B, 1.0);
		if (entry[1] >= 0)
			coarse_add(coarse, r, J, entry[1], B, 1.0);
		if (entry[2] >= 0) {
			// B is symmetric (the definite variant): the (J, I) block is the same.
			coarse_add(coarse, r, I, entry[2], B, -1.0);
			coarse_add(coarse, r, J, entry[3], B, -1.0);
		}
	}
	memset(r->coarse_mass, 0, (size_t)r->aggregate_count * sizeof(double));
	for (int32_t i = 0; i < m->particle_count; i++)
		if (r->aggregate[i] >= 0)
			r->coarse_mass[r->aggregate[i]] += m->mass[i];
	for (int32_t I = 0; I < r->aggregate_count; I++)
		for (int i = 0; i < 3; i++)
			coarse[sm_reduced_coarse_entry(r, I, r->coarse_self[I], i, i)] += r->coarse_mass[I] * damping;
	int status;
	if (r->multilevel != NULL) {
		status = sm_multilevel_refresh(r->multilevel, coarse, &r->common) ? 0 : 1;
	} else {
		// The symbolic analysis, once: in halves for a model in chunks (sm_reduced_split_coarse). Without it
		// (out of memory) nothing can be factorised at any step size: an error, not a matrix that
		// is not positive definite, which a smaller step may mend.
		if (r->coarse_factor == NULL && r->coarse_part != NULL)
			r->coarse_halves =
			    sm_coarse_halves_create(r->coarse, r->coarse_part, &r->coarse_factor, &r->common);
		else if (r->coarse_factor == NULL)
			r->coarse_factor = sm_cholmod_analyze(r->coarse, &r->common);
		if (r->coarse_factor == NULL)
			status = -1;
		else if (sm_cholmod_factorize(r->coarse, r->coarse_factor, &r->common) &&
		         r->common.status == CHOLMOD_OK)
			status = 0;
		else
			status = 1;
	}
	// A failed refresh is retried at the next preparation.
	r->coarse_age = status == 0 ? 0 : COARSE_MAX_AGE;
	return status;
}

// The scaled records and the inverted diagonal blocks, chunk by chunk (the springs between
// chunks on the caller's thread in between), then the coarse matrix if it is due (before the first
// refresh coarse_gamma is 0, so the ratio of the gammas is infinite and the test fails), or if the
// scale (sm_reduced_scale) differs from the coarse matrix's: all of them times the scale at gamma. Returns
// 0, 1 if a block is singular or the coarse matrix is not positive definite, -1 if out of memory.
int sm_reduced_prepare_preconditioner(sm_reduced* r, double gamma)
{
	preconditioner_job job = {.r = r, .gamma = gamma};
	sm_workers_run(r->workers, spring_shares_chunk, &job, r->chunks);
	add_spring_shares(r, gamma, r->chunk_spring[r->chunks], r->sim->model->spring_count);
	sm_workers_run(r->workers, invert_chunk, &job, r->chunks);
	for (int c = 0; c < r->chunks; c++)
		if (job.singular[c])
			return 1;
	if (!r->two_level)
		return 0;
	if (r->coarse_age >= COARSE_MAX_AGE || !(fabs(gamma / r->coarse_gamma - 1.0) <= COARSE_GAMMA_CHANGE) ||
	    r->coarse_scale != sm_reduced_scale(gamma))
		return refresh_coarse(r, gamma);
	r->coarse_age++;
	return 0;
}

typedef struct precondition_job {
	sm_reduced* r;
	const double* in;
	double* out;
	const double* yc;  // the coarse solution, for the prolongation
} precondition_job;

// Chunk c of block Jacobi (out_i = A_ii^-1 in_i, zero blocks at constrained particles) at its
// particles, with in . out when there is no coarse correction, and of the restriction
// P^T in at its aggregates, each summed over its members in order. The inverses are stored by
// column pairs (invert_chunk), so that the first two rows of a product are one SSE2 register
// (part of every x86-64 processor): out_x and out_y are m_0 in_x + m_1 in_y + m_2 in_z with the
// pairs m_0, m_1, m_2 of the first two rows' entries, each lane doing the scalar row's operations
// in their order, and the sums too, x and y in one register: the same bits as scalar loops.
static void block_jacobi_chunk(void* context, int c)
{
	const precondition_job* j = context;
	sm_reduced* r = j->r;
	const double* restrict inverse = r->block_inverse;
	const double* restrict in = j->in;
	double* restrict out = j->out;
	double sum = 0.0;
	for (int64_t k = r->chunk_particle[c]; k < r->chunk_particle[c + 1]; k++) {
		const double* m = inverse + 9 * k;
		const double* a = in + 3 * k;
		double* o = out + 3 * k;
#if defined(SM_REDUCED_SSE2)
		const __m128d oxy = _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_loadu_pd(m), _mm_set1_pd(a[0])),
		                                          _mm_mul_pd(_mm_loadu_pd(m + 2), _mm_set1_pd(a[1]))),
		                               _mm_mul_pd(_mm_loadu_pd(m + 4), _mm_set1_pd(a[2])));
		const double oz = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
		_mm_storeu_pd(o, oxy);
		o[2] = oz;
		const __m128d t = _mm_mul_pd(_mm_loadu_pd(a), oxy);
		sum += (_mm_cvtsd_f64(t) + _mm_cvtsd_f64(_mm_unpackhi_pd(t, t))) + a[2] * oz;
#else
		o[0] = m[0] * a[0] + m[2] * a[1] + m[4] * a[2];
		o[1] = m[1] * a[0] + m[3] * a[1] + m[5] * a[2];
		o[2] = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
		sum += a[0] * o[0] + a[1] * o[1] + a[2] * o[2];
#endif
	}
	r->partial[c] = sum;
	if (!r->two_level)
		return;
	double* restrict rc = r->coarse_b->x;
	const int32_t* restrict member = r->member;
	for (int32_t I = r->chunk_aggregate[c]; I < r->chunk_aggregate[c + 1]; I++) {
#if defined(SM_REDUCED_SSE2)
		__m128d xy = _mm_setzero_pd();
		double z = 0.0;
		for (int32_t e = r->member_first[I]; e < r->member_first[I + 1]; e++) {
			const double* a = in + 3 * (size_t)member[e];
			xy = _mm_add_pd(xy, _mm_loadu_pd(a));
			z += a[2];
		}
		_mm_storeu_pd(rc + 3 * (size_t)I, xy);
		rc[3 * (size_t)I + 2] = z;
#else
		double x = 0.0, y = 0.0, z = 0.0;
		for (int32_t e = r->member_first[I]; e < r->member_first[I + 1]; e++) {
			const double* a = in + 3 * (size_t)member[e];
			x += a[0], y += a[1], z += a[2];
		}
		rc[3 * (size_t)I] = x, rc[3 * (size_t)I + 1] = y, rc[3 * (size_t)I + 2] = z;
#endif
	}
}

// Chunk c of the prolongation out += P yc at its particles, with in . out.
static void prolongation_chunk(void* context, int c)
{
	const precondition_job* j = context;
	sm_reduced* r = j->r;
	const int32_t* restrict aggregate = r->aggregate;
	const double* restrict in = j->in;
	const double* restrict yc = j->yc;
	double* restrict out = j->out;
	double sum = 0.0;
	for (int64_t k = r->chunk_particle[c]; k < r->chunk_particle[c + 1]; k++) {
		const int32_t I = aggregate[k];
		if (I < 0)
			continue;
		const double* a = in + 3 * k;
		double* o = out + 3 * k;
#if defined(SM_REDUCED_SSE2)
		const __m128d oxy = _mm_add_pd(_mm_loadu_pd(o), _mm_loadu_pd(yc + 3 * (size_t)I));
		const double oz = o[2] + yc[3 * (size_t)I + 2];
		_mm_storeu_pd(o, oxy);
		o[2] = oz;
		const __m128d t = _mm_mul_pd(_mm_loadu_pd(a), oxy);
		sum += (_mm_cvtsd_f64(t) + _mm_cvtsd_f64(_mm_unpackhi_pd(t, t))) + a[2] * oz;
#else
		o[0] += yc[3 * (size_t)I];
		o[1] += yc[3 * (size_t)I + 1];
		o[2] += yc[3 * (size_t)I + 2];
		sum += a[0] * o[0] + a[1] * o[1] + a[2] * o[2];
#endif
	}
	r->partial[c] = sum;
}

// Applies the preconditioner, out = B in, and returns in . out in *dot: block Jacobi plus the
// coarse correction P A_c^-1 P^T in (additive). The restriction is summed in the block-Jacobi pass
// and the dot product in the prolongation's, so that each pass over the particles does all it can.
bool sm_reduced_apply_preconditioner(sm_reduced* r, const double* in, double* out, double* dot)
{
	precondition_job job = {r, in, out, NULL};
	sm_workers_run(r->workers, block_jacobi_chunk, &job, r->chunks);
	if (!r->two_level) {
		*dot = sm_reduced_sum_partials(r);
		return true;
	}
	if (r->multilevel != NULL) {
		job.yc =
		    sm_multilevel_solve(r->multilevel, r->coarse_b->x, COARSE_ITERATIONS, r->workers, &r->common);
		if (job.yc == NULL)
			return false;
	} else if (r->coarse_halves != NULL) {
		sm_coarse_halves_solve(r->coarse_halves, r->coarse_factor, r->coarse_b->x, r->coarse_solution,
		                       r->workers);
		job.yc = r->coarse_solution;
	} else {
		if (!sm_cholmod_solve(r->coarse_factor, r->coarse_b, &r->coarse_x, &r->coarse_y, &r->coarse_e,
		                      &r->common))
			return false;
		job.yc = r->coarse_x->x;
	}
	sm_workers_run(r->workers, prolongation_chunk, &job, r->chunks);
	*dot = sm_reduced_sum_partials(r);
	return true;
}

// Makes the next preparation sum and factorise the coarse matrix afresh (masses or springs may
// have changed).
void sm_reduced_forget_coarse(sm_reduced* r)
{
	r->coarse_age = COARSE_MAX_AGE;
}

// Products with the reduced solver's Newton matrix A = M (1 + gamma alpha) - gamma D - gamma^2 K
// and with -K, formed from the springs' records without assembling either.
//
// Derivation. A spring between particles a and b has the factored Jacobian blocks (forces.c,
// model_internal.h) K_s = d f_a / d x_b = u z^T + beta I and D_s = d f_a / d v_b = kd u u^T. Its
// force depends on x_b - x_a and v_b - v_a only, and f_b = -f_a, so it puts -K_s on the diagonal
// blocks (a, a), (b, b) of the model's K and +K_s on (a, b), (b, a); the same for D. Into A it
// therefore adds
//   B = gamma^2 K_s + gamma D_s = u w^T + gamma^2 beta I,  w = gamma^2 z + gamma kd u,
// at (a, a) and (b, b), and -B at (a, b) and (b, a). With r = p_b - p_a, its share of A p is -B r
// at a and +B r at b, where B r = u (w . r) + gamma^2 beta r: one dot product per spring. The
// same loop with w = z and c = beta (the Jacobian's own records) gives -K p.
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include <string.h>

#if defined(SM_REDUCED_SSE2)
#include <emmintrin.h>
#endif

// The springs at positions begin .. end of the chunk order added to q from their records, u[3],
// w[3], c (stride 8): with r = p_b - p_a, u (w . r) + c r subtracted at a and added at b (the
// derivation above). The
// scaled records give the share of A (w = gamma^2 z + gamma kd u, c = gamma^2 beta); the
// Jacobian's own give that of -K (w = z, c = beta; kd, the eighth entry, unread).
//
// Structures list their springs particle by particle, so consecutive springs often share
// their first particle: its sum and its p are kept in registers until the particle changes
// (holding p too: 1.6 % faster at n = 16, 1 - 2 % at n = 64 and 128). The entries' offsets
// (entry_a, entry_b: 3 a and 3 b) are precomputed.
#if defined(SM_REDUCED_SSE2)
// x and y in the two lanes of one SSE2 register (part of every x86-64 processor), z apart: the
// loop is bound by the instructions it issues, not by its loads or arithmetic, and this takes
// about a quarter fewer. Each lane performs the scalar loop's operations in the same order, and
// w . r is (w_x r_x + w_y r_y) + w_z r_z as there: the same bits.
#if defined(__GNUC__)
#define PRODUCTS_LOOP static inline __attribute__((always_inline))
#else
#define PRODUCTS_LOOP static inline
#endif
PRODUCTS_LOOP void spring_products_loop(const int32_t* restrict first, const int32_t* restrict second,
                                        const double* restrict records, const double* restrict p,
                                        double* restrict q, int32_t begin, int32_t end)
{
	int32_t held = first[begin];
	__m128d hxy = _mm_setzero_pd();
	double hz = 0.0;
	__m128d pxy = _mm_loadu_pd(p + held);
	double pz = p[held + 2];
	for (int32_t s = begin; s < end; s++) {
		const double* restrict e = records + SCALED_STRIDE * (size_t)s;
		const int32_t a = first[s];
		if (a != held) {
			_mm_storeu_pd(q + held, _mm_sub_pd(_mm_loadu_pd(q + held), hxy));
			q[held + 2] -= hz;
			hxy = _mm_setzero_pd();
			hz = 0.0;
			held = a;
			pxy = _mm_loadu_pd(p + a);
			pz = p[a + 2];
		}
		const int32_t b = second[s];
		const __m128d rxy = _mm_sub_pd(_mm_loadu_pd(p + b), pxy);
		const double rz = p[b + 2] - pz;
		const __m128d t = _mm_mul_pd(_mm_loadu_pd(e + 3), rxy);
		const double c = (_mm_cvtsd_f64(t) + _mm_cvtsd_f64(_mm_unpackhi_pd(t, t))) + e[5] * rz;
		const __m128d fxy =
		    _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(e), _mm_set1_pd(c)), _mm_mul_pd(_mm_set1_pd(e[6]), rxy));
		const double fz = e[2] * c + e[6] * rz;
		hxy = _mm_add_pd(hxy, fxy);
		hz += fz;
		_mm_storeu_pd(q + b, _mm_add_pd(_mm_loadu_pd(q + b), fxy));
		q[b + 2] += fz;
	}
	_mm_storeu_pd(q + held, _mm_sub_pd(_mm_loadu_pd(q + held), hxy));
	q[held + 2] -= hz;
}

static void spring_products_sse2(const int32_t* first, const int32_t* second, const double* records,
                                 const double* p, double* q, int32_t begin, int32_t end)
{
	spring_products_loop(first, second, records, p, q, begin, end);
}

#if defined(__x86_64__) && defined(__GNUC__)
// The same loop compiled for AVX where the processor has it (chosen at run time, as forces.c
// does): the same operations in three-operand encodings, without the register copies SSE2's
// two-operand ones need, hence the same bits. The target enables neither FMA nor reassociation.
static __attribute__((target("avx"))) void spring_products_avx(const int32_t* first, const int32_t* second,
                                                               const double* records, const double* p,
                                                               double* q, int32_t begin, int32_t end)
{
	spring_products_loop(first, second, records, p, q, begin, end);
}
#endif

static void add_spring_products(const sm_reduced* r, const double* records, const double* p,
                                double* restrict q, int32_t begin, int32_t end)
{
	if (begin >= end)
		return;
#if defined(__x86_64__) && defined(__GNUC__)
	if (__builtin_cpu_supports("avx")) {
		spring_products_avx(r->entry_a, r->entry_b, records, p, q, begin, end);
		return;
	}
#endif
	spring_products_sse2(r->entry_a, r->entry_b, records, p, q, begin, end);
}
#else
static void add_spring_products(const sm_reduced* r, const double* records, const double* p,
                                double* restrict q, int32_t begin, int32_t end)
{
	const int32_t* restrict first = r->entry_a;
	const int32_t* restrict second = r->entry_b;
	if (begin >= end)
		return;
	int32_t held = first[begin];
	double hx = 0.0, hy = 0.0, hz = 0.0;
	double px = p[held], py = p[held + 1], pz = p[held + 2];
	for (int32_t s = begin; s < end; s++) {
		const double* restrict e = records + SCALED_STRIDE * (size_t)s;
		const int32_t a = first[s];
		if (a != held) {
			q[held] -= hx;
			q[held + 1] -= hy;
			q[held + 2] -= hz;
			hx = hy = hz = 0.0;
			held = a;
			px = p[a], py = p[a + 1], pz = p[a + 2];
		}
		const int32_t b = second[s];
		const double rx = p[b] - px, ry = p[b + 1] - py, rz = p[b + 2] - pz;
		const double c = e[3] * rx + e[4] * ry + e[5] * rz;
		const double fx = e[0] * c + e[6] * rx, fy = e[1] * c + e[6] * ry, fz = e[2] * c + e[6] * rz;
		hx += fx;
		hy += fy;
		hz += fz;
		q[b] += fx;
		q[b + 1] += fy;
		q[b + 2] += fz;
	}
	q[held] -= hx;
	q[held + 1] -= hy;
	q[held + 2] -= hz;
}
#endif

typedef struct product_job {
	sm_reduced* r;
	const double* p;
	double* q;
} product_job;

// Chunk c of q = A p (pcg): the mass term at its particles, then its springs, which reach no
// other chunk's particles.
static void product_chunk(void* context, int c)
{
	const product_job* j = context;
	const sm_reduced* r = j->r;
	const double damping = r->scale + r->scale * r->gamma * r->sim->model->def.mass_damping;
	const double* restrict p = j->p;
	const double* restrict mass = r->mass;
	double* restrict q = j->q;
	for (int64_t i = 3 * (int64_t)r->chunk_particle[c]; i < 3 * (int64_t)r->chunk_particle[c + 1]; i++)
		q[i] = mass[i] * damping * p[i];
	add_spring_products(r, r->scaled, p, q, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

// Chunk c of q = -K p (the Jacobian's records): zero at its particles, then its springs.
static void stiffness_chunk(void* context, int c)
{
	const product_job* j = context;
	const sm_reduced* r = j->r;
	memset(j->q + 3 * (size_t)r->chunk_particle[c], 0,
	       3 * (size_t)(r->chunk_particle[c + 1] - r->chunk_particle[c]) * sizeof(double));
	add_spring_products(r, r->springs->data, j->p, j->q, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

typedef struct dot_job {
	sm_reduced* r;
	const double* a;
	const double* b;
} dot_job;

static void dot_chunk(void* context, int c)
{
	const dot_job* j = context;
	const double* restrict a = j->a;
	const double* restrict b = j->b;
	double s = 0.0;
	for (int64_t i = 3 * (int64_t)j->r->chunk_particle[c]; i < 3 * (int64_t)j->r->chunk_particle[c + 1]; i++)
		s += a[i] * b[i];
	j->r->partial[c] = s;
}

// a . b over all particles, chunk by chunk, the chunks' sums added in chunk order.
double sm_reduced_dot(sm_reduced* r, const double* a, const double* b)
{
	dot_job job = {r, a, b};
	sm_workers_run(r->workers, dot_chunk, &job, r->chunks);
	return sm_reduced_sum_partials(r);
}

// q = A p = M (1 + gamma alpha) p - gamma D p - gamma^2 K p over all particles, times the solve's
// scale (p is zero at the constrained ones, whose entries of q are set to zero); returns p . q.
//
// With pcg, each spring's share comes from its scaled record (u, w, gamma^2 beta, written by the
// preconditioner's preparation at the same gamma, which must precede the product,
// reduced_preconditioner.c): B r, subtracted at a and added at b, one dot product per spring
// where the unscaled records need two and four more multiplications. Measured on the benchmark
// cloth's springs (definite variant, medians of 9 timings): 0.78 - 0.79 of the time of
// sm_spring_jacobians_combined_product at n = 16, 64 and 128; the records cost nothing extra to
// write, being summed into the preconditioner in the same pass anyway. With cholmod (no
// preconditioner pass) the unscaled records serve.
double sm_reduced_multiply(sm_reduced* r, const double* p, double* restrict q)
{
	const double g = r->gamma, scaled = r->scale * g;
	const sm_simulation* sim = r->sim;
	if (r->use_cholmod) {
		sm_spring_jacobians_combined_product(r->springs, sim->model, scaled * g, scaled, p, q);
		for (int64_t i = 0; i < r->full; i++)
			q[i] = r->mass[i] * r->scale * p[i] - q[i];
	} else {
		product_job job = {r, p, q};
		sm_workers_run(r->workers, product_chunk, &job, r->chunks);
		add_spring_products(r, r->scaled, p, q, r->chunk_spring[r->chunks], sim->model->spring_count);
	}
	for (int32_t k = 0; k < sim->constrained_count; k++)
		memset(q + 3 * (size_t)sim->constrained[k], 0, 3 * sizeof(double));
	return sm_reduced_dot(r, p, q);
}

// q = -K p over all particles from the Jacobian's records, chunk by chunk, the springs between
// chunks after them on the caller's thread; the constrained particles' entries are left as the
// springs make them (the caller clears them).
void sm_reduced_stiffness_product(sm_reduced* r, const double* p, double* q)
{
	product_job job = {r, p, q};
	sm_workers_run(r->workers, stiffness_chunk, &job, r->chunks);
	add_spring_products(r, r->springs->data, p, q, r->chunk_spring[r->chunks], r->sim->model->spring_count);
}

// Jacobians of the physics core against central finite differences of the forces: per-spring
// blocks, dense matrices, the Jacobian-vector product and the assembled sparse matrix, plus the
// definiteness-preserving variant's symmetry and sign.
//
// Finite differences: central, step h = 1e-6 (positions are O(1) m, velocities O(1) m/s). The
// truncation error is h^2/6 |f'''|; with springs no shorter than about 0.05 m, stiffness up to
// 200 N/m and f''' ~ ks l0 / L^3 <= 1e5 N/m^3 that is <= 2e-8 N/m. Rounding adds about
// eps |f| / h = 2.2e-16 * 1e2 / 1e-6 ~ 2e-8. So every comparison allows 1e-6 times the largest
// entry of the matrix involved (at least 1): a margin of ~50 over the expected error, while a
// wrong term (e.g. a missing damping-position derivative, O(kd |dv| / L) ~ 1..100) is caught.
#include "physics_fixtures.h"
#include "springmass/model.h"
#include "test_harness.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <stdlib.h>

#define FD_STEP 1e-6
#define FD_RELATIVE 1e-6

static double max_abs(const double* a, size_t n)
{
	double m = 1.0;
	for (size_t i = 0; i < n; i++)
		m = fmax(m, fabs(a[i]));
	return m;
}

// Column j of d f / d (x or v) by central differences: out[3n].
static void fd_column(const sm_model* m, double* x, double* v, int wrt_velocity, size_t j, double* out)
{
	const size_t dim = 3 * (size_t)sm_model_particle_count(m);
	double* fp = malloc(dim * sizeof(double));
	double* fm = malloc(dim * sizeof(double));
	double* s = wrt_velocity ? v : x;
	const double keep = s[j];
	s[j] = keep + FD_STEP;
	sm_model_forces(m, x, v, NULL, fp);
	s[j] = keep - FD_STEP;
	sm_model_forces(m, x, v, NULL, fm);
	s[j] = keep;
	for (size_t i = 0; i < dim; i++)
		out[i] = (fp[i] - fm[i]) / (2.0 * FD_STEP);
	free(fp);
	free(fm);
}

// A two-particle model holding only spring s of `from` (no gravity, no mass damping), so that
// the force on particle 0 is exactly f_a of that spring.
static sm_model* single_spring(const sm_model* from, int32_t s, const double* x, const double* v, double* x2,
                               double* v2)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* m = sm_model_create(&md, NULL);
	sm_spring_def d;
	sm_model_get_spring(from, s, &d);
	const int32_t ends[2] = {d.a, d.b};
	for (int e = 0; e < 2; e++) {
		sm_particle_def p = sm_default_particle_def();
		for (int k = 0; k < 3; k++) {
			p.position[k] = x2[3 * e + k] = x[3 * ends[e] + k];
			p.velocity[k] = v2[3 * e + k] = v[3 * ends[e] + k];
		}
		sm_model_add_particle(m, &p, NULL);
	}
	d.a = 0;
	d.b = 1;
	sm_model_add_spring(m, &d, NULL);
	return m;
}

static int test_spring_blocks_match_finite_differences(void)
{
	rng r = {12345};
	for (int trial = 0; trial < 20; trial++) {
		double x[3 * 8], v[3 * 8];
		sm_model* m = random_model(&r, 8, 14, 0, x, v);
		ENSURE(m != NULL);
		for (int32_t s = 0; s < sm_model_spring_count(m); s++) {
			double K[9], D[9], x2[6], v2[6], col[6];
			ENSURE_STATUS(sm_model_spring_jacobian(m, s, x, v, SM_JACOBIAN_EXACT, K, D), SM_OK);
			sm_model* one = single_spring(m, s, x, v, x2, v2);
			ENSURE(one != NULL);
			const double scale_k = max_abs(K, 9), scale_d = max_abs(D, 9);
			for (int j = 0; j < 3; j++) {
				fd_column(one, x2, v2, 0, 3 + (size_t)j, col);  // d f / d x_b, column j
				for (int i = 0; i < 3; i++)
					ENSURE_NEAR(K[3 * i + j], col[i], FD_RELATIVE * scale_k);
				fd_column(one, x2, v2, 1, 3 + (size_t)j, col);  // d f / d v_b, column j
				for (int i = 0; i < 3; i++)
					ENSURE_NEAR(D[3 * i + j], col[i], FD_RELATIVE * scale_d);
			}
			sm_model_destroy(one);
		}
		sm_model_destroy(m);
	}
	return 0;
}

static int test_dense_jacobians_match_finite_differences(void)
{
	rng r = {777};
	for (int trial = 0; trial < 10; trial++) {
		enum { N = 7 };
		double x[3 * N], v[3 * N], col[3 * N];
		sm_model* m = random_model(&r, N, 12, 1, x, v);
		ENSURE(m != NULL);
		const size_t dim = 3 * N;
		double* dfdx = malloc(dim * dim * sizeof(double));
		double* dfdv = malloc(dim * dim * sizeof(double));
		sm_model_jacobian_dense(m, x, v, SM_JACOBIAN_EXACT, dfdx, dfdv);
		const double sx = max_abs(dfdx, dim * dim), sv = max_abs(dfdv, dim * dim);
		for (size_t j = 0; j < dim; j++) {
			fd_column(m, x, v, 0, j, col);
			for (size_t i = 0; i < dim; i++)
				ENSURE_NEAR(dfdx[i * dim + j], col[i], FD_RELATIVE * sx);
			fd_column(m, x, v, 1, j, col);
			for (size_t i = 0; i < dim; i++)
				ENSURE_NEAR(dfdv[i * dim + j], col[i], FD_RELATIVE * sv);
		}
		free(dfdx);
		free(dfdv);
		sm_model_destroy(m);
	}
	return 0;
}

// The product must equal the dense matrices applied to the vectors; both are sums of the same
// few terms, so they agree to rounding: 1e-12 of the largest term.
static int test_jacobian_product_matches_dense(void)
{
	rng r = {4242};
	enum { N = 9 };
	const size_t dim = 3 * N;
	double x[3 * N], v[3 * N], dx[3 * N], dv[3 * N], out[3 * N], expect[3 * N];
	double* dfdx = malloc(dim * dim * sizeof(double));
	double* dfdv = malloc(dim * dim * sizeof(double));
	for (int trial = 0; trial < 10; trial++) {
		sm_model* m = random_model(&r, N, 20, trial % 2, x, v);
		ENSURE(m != NULL);
		for (size_t k = 0; k < dim; k++) {
			dx[k] = rng_uniform(&r, -1, 1);
			dv[k] = rng_uniform(&r, -1, 1);
		}
		for (int variant = 0; variant < 2; variant++) {
			sm_model_jacobian_dense(m, x, v, (sm_jacobian_variant)variant, dfdx, dfdv);
			const double scale = fmax(max_abs(dfdx, dim * dim), max_abs(dfdv, dim * dim)) * dim;
			for (int which = 0; which < 3; which++) {  // both, dx only, dv only
				const double* px = which == 2 ? NULL : dx;
				const double* pv = which == 1 ? NULL : dv;
				sm_model_jacobian_product(m, x, v, (sm_jacobian_variant)variant, px, pv, out);
				for (size_t i = 0; i < dim; i++) {
					expect[i] = 0.0;
					for (size_t j = 0; j < dim; j++)
						expect[i] +=
						    (px ? dfdx[i * dim + j] * px[j] : 0.0) + (pv ? dfdv[i * dim + j] * pv[j] : 0.0);
					ENSURE_NEAR(out[i], expect[i], 1e-12 * scale);
				}
			}
		}
		sm_model_destroy(m);
	}
	free(dfdx);
	free(dfdv);
	return 0;
}

// Expands a CSR matrix into a dense dim x dim one.
static void csr_to_dense(int64_t dim, const int64_t* rows, const int64_t* cols, const double* values,
                         double* dense)
{
	memset(dense, 0, (size_t)(dim * dim) * sizeof(double));
	for (int64_t i = 0; i < dim; i++)
		for (int64_t k = rows[i]; k < rows[i + 1]; k++)
			dense[i * dim + cols[k]] += values[k];
}

static int test_sparse_jacobian_pattern_and_values(void)
{
	rng r = {99};
	enum { N = 10 };
	double x[3 * N], v[3 * N], col[3 * N];
	for (int trial = 0; trial < 6; trial++) {
		sm_model* m = random_model(&r, N, 18, 1, x, v);
		ENSURE(m != NULL);
		// A second spring between particles 0 and 1 (a duplicate pair shares its blocks), a
		// spring between the fixed particle and a free one, and one more fixed particle.
		sm_spring_def d = sm_default_spring_def();
		d.a = 1;
		d.b = 0;
		d.stiffness = 33.0;
		d.damping = 0.4;
		ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		d.a = N - 1;
		d.b = 3;
		ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		ENSURE_STATUS(sm_model_set_particle_motion(m, 5, SM_PARTICLE_FIXED), SM_OK);
		v[15] = v[16] = v[17] = 0.0;
		ENSURE(sm_model_free_count(m) == N - 2);

		sm_sparse_jacobian* J = sm_sparse_jacobian_create(m);
		ENSURE(J != NULL);
		const int64_t dim = sm_sparse_jacobian_dimension(J), nnz = sm_sparse_jacobian_nonzeros(J);
		const int64_t* rows = sm_sparse_jacobian_row_pointers(J);
		const int64_t* cols = sm_sparse_jacobian_column_indices(J);
		ENSURE(dim == 3 * (N - 2));
		ENSURE(rows[0] == 0 && rows[dim] == nnz);
		for (int64_t i = 0; i < dim; i++) {
			int diagonal = 0;
			ENSURE(rows[i + 1] > rows[i]);
			for (int64_t k = rows[i]; k < rows[i + 1]; k++) {
				ENSURE(cols[k] >= 0 && cols[k] < dim);
				if (k > rows[i])
					ENSURE(cols[k] > cols[k - 1]);  // sorted, no duplicates
				diagonal |= cols[k] == i;
			}
			ENSURE(diagonal);
		}

		double* sx = malloc((size_t)nnz * sizeof(double));
		double* sv = malloc((size_t)nnz * sizeof(double));
		double* ax = malloc((size_t)(dim * dim) * sizeof(double));
		double* av = malloc((size_t)(dim * dim) * sizeof(double));
		ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, sx, sv), SM_OK);
		csr_to_dense(dim, rows, cols, sx, ax);
		csr_to_dense(dim, rows, cols, sv, av);
		// Against finite differences over the free degrees of freedom.
		const double scale_x = max_abs(ax, (size_t)(dim * dim)), scale_v = max_abs(av, (size_t)(dim * dim));
		for (int32_t q = 0; q < N; q++) {
			const int32_t fq = sm_model_free_index(m, q);
			if (fq < 0)
				continue;
			for (int c = 0; c < 3; c++) {
				for (int wrt = 0; wrt < 2; wrt++) {
					fd_column(m, x, v, wrt, 3 * (size_t)q + c, col);
					const double* a = wrt ? av : ax;
					for (int32_t p = 0; p < N; p++) {
						const int32_t fp = sm_model_free_index(m, p);
						if (fp < 0)
							continue;
						for (int i = 0; i < 3; i++)
							ENSURE_NEAR(a[(3 * fp + i) * dim + 3 * fq + c], col[3 * p + i],
							            FD_RELATIVE * (wrt ? scale_v : scale_x));
					}
				}
			}
		}
		// Changing constants or disabling keeps the pattern; changing a motion does not.
		ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
		ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_DEFINITE, sx, NULL), SM_OK);
		ENSURE_STATUS(sm_model_set_particle_motion(m, 2, SM_PARTICLE_DRIVEN), SM_OK);
		ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, sx, sv), SM_ERROR_TOPOLOGY);
		free(sx);
		free(sv);
		free(ax);
		free(av);
		sm_sparse_jacobian_destroy(J);
		sm_model_destroy(m);
	}
	sm_sparse_jacobian_destroy(NULL);
	return 0;
}

// The definite variant: df/dx symmetric with no positive eigenvalue (computed by GSL's
// symmetric eigensolver; its backward error is ~ eps * ||K||, so 1e-10 of the largest entry
// bounds eigenvalues that are zero in exact arithmetic, e.g. rigid-body modes).
static int test_definite_variant_is_symmetric_negative_semidefinite(void)
{
	rng r = {2024};
	enum { N = 8 };
	const size_t dim = 3 * N;
	double x[3 * N], v[3 * N];
	double* K = malloc(dim * dim * sizeof(double));
	gsl_eigen_symm_workspace* w = gsl_eigen_symm_alloc(dim);
	gsl_vector* eval = gsl_vector_alloc(dim);
	for (int trial = 0; trial < 20; trial++) {
		sm_model* m = random_model(&r, N, 16, 0, x, v);
		ENSURE(m != NULL);
		sm_model_jacobian_dense(m, x, v, SM_JACOBIAN_DEFINITE, K, NULL);
		const double scale = max_abs(K, dim * dim);
		for (size_t i = 0; i < dim; i++)
			for (size_t j = 0; j < i; j++)
				ENSURE_NEAR(K[i * dim + j], K[j * dim + i], 1e-14 * scale);
		gsl_matrix_view a = gsl_matrix_view_array(K, dim, dim);
		ENSURE(gsl_eigen_symm(&a.matrix, eval, w) == 0);
		for (size_t i = 0; i < dim; i++)
			ENSURE(gsl_vector_get(eval, i) <= 1e-10 * scale);
		// The exact variant of a model with compressed springs does have a positive eigenvalue
		// somewhere among the trials (the buckling the clamp removes); not asserted per trial.
		sm_model_destroy(m);
	}
	gsl_vector_free(eval);
	gsl_eigen_symm_free(w);
	free(K);
	return 0;
}

// For stretched springs at rest the clamp is inactive and the damping-position term vanishes
// (r = 0, dv = 0): both variants are the same numbers (same formulas, so equal to rounding).
static int test_definite_equals_exact_for_stretched_springs_at_rest(void)
{
	rng r = {31337};
	enum { N = 6 };
	const size_t dim = 3 * N;
	double x[3 * N], v[3 * N], stretched_x[3 * N], zero_v[3 * N] = {0};
	double* ke = malloc(dim * dim * sizeof(double));
	double* kd = malloc(dim * dim * sizeof(double));
	double* de = malloc(dim * dim * sizeof(double));
	double* dd = malloc(dim * dim * sizeof(double));
	sm_model* m = random_model(&r, N, 10, 0, x, v);
	ENSURE(m != NULL);
	// Scale the configuration by 2 about the origin: every spring (l0 <= 1.5 L) is then stretched.
	for (size_t k = 0; k < dim; k++)
		stretched_x[k] = 2.0 * x[k];
	sm_model_jacobian_dense(m, stretched_x, zero_v, SM_JACOBIAN_EXACT, ke, de);
	sm_model_jacobian_dense(m, stretched_x, zero_v, SM_JACOBIAN_DEFINITE, kd, dd);
	const double scale = max_abs(ke, dim * dim);
	for (size_t k = 0; k < dim * dim; k++) {
		ENSURE_NEAR(ke[k], kd[k], 1e-14 * scale);
		ENSURE(de[k] == dd[k]);
	}
	// With compressed springs they must differ (the clamp is active).
	sm_model_jacobian_dense(m, x, zero_v, SM_JACOBIAN_EXACT, ke, NULL);
	sm_model_jacobian_dense(m, x, zero_v, SM_JACOBIAN_DEFINITE, kd, NULL);
	double diff = 0.0;
	for (size_t k = 0; k < dim * dim; k++)
		diff = worst_of(diff, fabs(ke[k] - kd[k]));
	ENSURE(diff > 1.0);
	sm_model_destroy(m);
	free(ke);
	free(kd);
	free(de);
	free(dd);
	return 0;
}

// At L = 0 the blocks are finite: ks I for both kinds, D = 0 (model.h).
static int test_degenerate_blocks_are_finite(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* m = sm_model_create(&md, NULL);
	sm_particle_def p = sm_default_particle_def();
	p.position[0] = 0.3;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 1;
	d.rest_length = 0.5;
	d.stiffness = 10.0;
	d.damping = 2.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	d.kind = SM_SPRING_ZERO_LENGTH;
	d.rest_length = 0.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	const double x[6] = {0.3, 0, 0, 0.3, 0, 0}, v[6] = {1, 2, 3, -1, 0, 4};
	for (int variant = 0; variant < 2; variant++)
		for (int32_t s = 0; s < 2; s++) {
			double K[9], D[9];
			ENSURE_STATUS(sm_model_spring_jacobian(m, s, x, v, (sm_jacobian_variant)variant, K, D), SM_OK);
			for (int k = 0; k < 9; k++) {
				ENSURE(K[k] == (k % 4 == 0 ? 10.0 : 0.0));
				ENSURE(D[k] == 0.0);
			}
		}
	double f[6];
	sm_model_forces(m, x, v, NULL, f);
	for (int k = 0; k < 6; k++)
		ENSURE(isfinite(f[k]));
	sm_model_destroy(m);
	return 0;
}

// A disabled spring contributes nothing; re-enabling restores its blocks exactly.
static int test_disabled_spring_has_zero_blocks(void)
{
	rng r = {5};
	double x[3 * 4], v[3 * 4], K0[9], D0[9], K[9], D[9];
	sm_model* m = random_model(&r, 4, 4, 0, x, v);
	ENSURE(m != NULL);
	ENSURE_STATUS(sm_model_spring_jacobian(m, 2, x, v, SM_JACOBIAN_EXACT, K0, D0), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 2, false), SM_OK);
	ENSURE_STATUS(sm_model_spring_jacobian(m, 2, x, v, SM_JACOBIAN_EXACT, K, D), SM_OK);
	for (int k = 0; k < 9; k++)
		ENSURE(K[k] == 0.0 && D[k] == 0.0);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 2, true), SM_OK);
	ENSURE_STATUS(sm_model_spring_jacobian(m, 2, x, v, SM_JACOBIAN_EXACT, K, D), SM_OK);
	for (int k = 0; k < 9; k++)
		ENSURE(K[k] == K0[k] && D[k] == D0[k]);
	// An error gives zero blocks, as a disabled spring does, not what the caller's memory held.
	ENSURE_STATUS(sm_model_spring_jacobian(m, 4, x, v, SM_JACOBIAN_EXACT, K, D), SM_ERROR_SPRING_INDEX);
	for (int k = 0; k < 9; k++)
		ENSURE(K[k] == 0.0 && D[k] == 0.0);
	for (int k = 0; k < 9; k++)
		K[k] = D[k] = NAN;
	ENSURE_STATUS(sm_model_spring_jacobian(m, 2, NULL, v, SM_JACOBIAN_EXACT, K, D),
	              SM_ERROR_INVALID_ARGUMENT);
	for (int k = 0; k < 9; k++)
		ENSURE(K[k] == 0.0 && D[k] == 0.0);
	sm_model_destroy(m);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// Forces and per-spring Jacobians in one pass (sm_model_forces_and_jacobians and what applies
// its factored records).
// ---------------------------------------------------------------------------------------------

// The fused pass computes the forces with the same expressions as sm_model_forces, so they are
// the same numbers bit for bit, whichever variant, with or without velocities and external forces.
static int test_fused_forces_equal_forces_exactly(void)
{
	rng r = {8080};
	enum { N = 9 };
	double x[3 * N], v[3 * N], ext[3 * N], f[3 * N], g[3 * N];
	for (int trial = 0; trial < 6; trial++) {
		sm_model* m = random_model(&r, N, 20, trial % 2, x, v);
		ENSURE(m != NULL);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		for (size_t k = 0; k < 3 * N; k++)
			ext[k] = rng_uniform(&r, -2.0, 2.0);
		for (int variant = 0; variant < 2; variant++)
			for (int with_v = 0; with_v < 2; with_v++)
				for (int with_ext = 0; with_ext < 2; with_ext++) {
					const double* pv = with_v ? v : NULL;
					const double* pe = with_ext ? ext : NULL;
					sm_model_forces(m, x, pv, pe, f);
					ENSURE_STATUS(
					    sm_model_forces_and_jacobians(m, x, pv, pe, (sm_jacobian_variant)variant, g, sj),
					    SM_OK);
					for (size_t k = 0; k < 3 * N; k++)
						ENSURE(f[k] == g[k]);
				}
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	return 0;
}

// Each spring's blocks rebuilt from its record against central finite differences of the force
// of that spring alone (exact variant; same tolerance argument as the file's header), and both
// variants against sm_model_spring_jacobian: the two evaluate K = beta I + u z^T and
// ks [u u^T + g P] + ... with different groupings of the same O(|K|) terms, so they agree to a
// few rounding errors of the largest entry; 1e-12 of it leaves a margin of ~50 over 2.2e-16 * 9.
static int test_fused_spring_blocks_match_finite_differences(void)
{
	rng r = {2468};
	for (int trial = 0; trial < 20; trial++) {
		double x[3 * 8], v[3 * 8], f[3 * 8];
		sm_model* m = random_model(&r, 8, 14, trial % 2, x, v);
		ENSURE(m != NULL);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		for (int variant = 0; variant < 2; variant++) {
			ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
			              SM_OK);
			for (int32_t s = 0; s < sm_model_spring_count(m); s++) {
				double K[9], D[9], K0[9], D0[9];
				ENSURE_STATUS(sm_spring_jacobians_block(sj, s, K, D), SM_OK);
				ENSURE_STATUS(sm_model_spring_jacobian(m, s, x, v, (sm_jacobian_variant)variant, K0, D0),
				              SM_OK);
				const double scale_k = max_abs(K0, 9), scale_d = max_abs(D0, 9);
				for (int k = 0; k < 9; k++) {
					ENSURE_NEAR(K[k], K0[k], 1e-12 * scale_k);
					ENSURE_NEAR(D[k], D0[k], 1e-12 * scale_d);
				}
				if (variant != SM_JACOBIAN_EXACT)
					continue;
				double x2[6], v2[6], col[6];
				sm_model* one = single_spring(m, s, x, v, x2, v2);
				ENSURE(one != NULL);
				for (int j = 0; j < 3; j++) {
					fd_column(one, x2, v2, 0, 3 + (size_t)j, col);
					for (int i = 0; i < 3; i++)
						ENSURE_NEAR(K[3 * i + j], col[i], FD_RELATIVE * scale_k);
					fd_column(one, x2, v2, 1, 3 + (size_t)j, col);
					for (int i = 0; i < 3; i++)
						ENSURE_NEAR(D[3 * i + j], col[i], FD_RELATIVE * scale_d);
				}
				sm_model_destroy(one);
			}
		}
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	return 0;
}

// The blocks of one spring at states where finite differences fail (lengths from 1e-9 to 1e3
// times the rest length, an axis missed by 1e-15, stiffness 1e-12 and 1e12, particles 1e6 m from
// the origin, damping far above the elastic force) against the closed form, evaluated in long
// double from the same coordinates. With d = x_b - x_a, L = |d|, u = d / L, w = v_b - v_a,
// r = u.w and P = I - u u^T, f_a = ks (L - l0) u + kd r u gives
//   K = d f_a / d x_b = ks ((1 - l0/L) I + (l0/L) u u^T) + (kd / L) (r P + u (P w)^T),
//   D = d f_a / d v_b = kd u u^T
// (a zero-length spring: l0 = 0). Both the direct blocks and the fused records are held to 1e-13
// of the block's largest entry: the forms differ only in rounding order (a few eps of each term,
// 6e-16 measured at worst), while a term dropped or mis-signed at these states (the l0 / L
// factor, the damping's position derivative) is of the order of the block.
static int test_spring_blocks_at_hard_states_match_the_closed_form(void)
{
	typedef struct hard_state {
		sm_spring_kind kind;
		double stiffness, damping, rest_length, offset;
		double d[3], w[3];
	} hard_state;
	const hard_state cases[] = {
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 0.0, {1e-9, 0.0, 0.0}, {0.3, -0.2, 0.1}},
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 0.0, {6e-4, -8e-4, 0.0}, {0.3, -0.2, 0.1}},
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 0.0, {0.6, 0.0, 0.8}, {0.0, 1.0, 0.0}},
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 0.0, {600.0, 0.0, 800.0}, {1.0, 1.0, 1.0}},
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 0.0, {1.0, 1e-15, -1e-15}, {0.0, 2.0, -1.0}},
	    {SM_SPRING_REST_LENGTH, 1e12, 0.0, 0.5, 0.0, {0.3, 0.2, 0.1}, {0.0, 0.0, 0.0}},
	    {SM_SPRING_REST_LENGTH, 1e-12, 1e-12, 0.5, 0.0, {0.3, 0.2, 0.1}, {1.0, 0.0, 0.0}},
	    {SM_SPRING_REST_LENGTH, 100.0, 2.0, 1.0, 1e6, {0.7, -0.4, 0.5}, {0.2, 0.1, -0.3}},
	    {SM_SPRING_REST_LENGTH, 1.0, 50.0, 1.0, 0.0, {0.9, 0.1, -0.2}, {370.0, -20.0, 5.0}},
	    {SM_SPRING_ZERO_LENGTH, 100.0, 2.0, 0.0, 0.0, {1e-9, 2e-9, 0.0}, {0.3, -0.2, 0.1}},
	    {SM_SPRING_ZERO_LENGTH, 100.0, 2.0, 0.0, 1e6, {0.7, -0.4, 0.5}, {0.2, 0.1, -0.3}},
	};
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		const hard_state* h = &cases[c];
		sm_model_def md = sm_default_model_def();
		md.gravity[2] = 0.0;
		sm_model* m = sm_model_create(&md, NULL);
		ENSURE(m != NULL);
		double x[6], v[6] = {0}, f[6];
		for (int e = 0; e < 2; e++) {
			sm_particle_def p = sm_default_particle_def();
			for (int k = 0; k < 3; k++) {
				p.position[k] = x[3 * e + k] = h->offset + (e == 1 ? h->d[k] : 0.0);
				p.velocity[k] = v[3 * e + k] = e == 1 ? h->w[k] : 0.0;
			}
			ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
		}
		sm_spring_def sd = sm_default_spring_def();
		sd.a = 0;
		sd.b = 1;
		sd.kind = h->kind;
		sd.rest_length = h->rest_length;
		sd.stiffness = h->stiffness;
		sd.damping = h->damping;
		ENSURE_STATUS(sm_model_add_spring(m, &sd, NULL), SM_OK);

		long double d[3], w[3], L2 = 0.0L, r = 0.0L;
		for (int k = 0; k < 3; k++) {
			d[k] = (long double)x[3 + k] - (long double)x[k];
			w[k] = (long double)v[3 + k] - (long double)v[k];
			L2 += d[k] * d[k];
		}
		const long double L = sqrtl(L2), ratio = h->rest_length / L;
		long double u[3], Pw[3];
		for (int k = 0; k < 3; k++)
			r += (u[k] = d[k] / L) * w[k];
		for (int k = 0; k < 3; k++)
			Pw[k] = w[k] - r * u[k];
		double K_ref[9], D_ref[9];
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				const long double delta = i == j ? 1.0L : 0.0L;
				K_ref[3 * i + j] = (double)(h->stiffness * ((1.0L - ratio) * delta + ratio * u[i] * u[j]) +
				                            h->damping / L * (r * (delta - u[i] * u[j]) + u[i] * Pw[j]));
				D_ref[3 * i + j] = (double)(h->damping * u[i] * u[j]);
			}

		double K[9], D[9];
		ENSURE_STATUS(sm_model_spring_jacobian(m, 0, x, v, SM_JACOBIAN_EXACT, K, D), SM_OK);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_OK);
		double K_fused[9], D_fused[9];
		ENSURE_STATUS(sm_spring_jacobians_block(sj, 0, K_fused, D_fused), SM_OK);
		double scale_k = 0.0, scale_d = 0.0;  // not max_abs's floor of 1: stiffness 1e-12 is here
		for (int k = 0; k < 9; k++) {
			scale_k = fmax(scale_k, fabs(K_ref[k]));
			scale_d = fmax(scale_d, fabs(D_ref[k]));
		}
		for (int k = 0; k < 9; k++) {
			ENSURE_NEAR(K[k], K_ref[k], 1e-13 * scale_k);
			ENSURE_NEAR(K_fused[k], K_ref[k], 1e-13 * scale_k);
			ENSURE_NEAR(D[k], D_ref[k], 1e-13 * scale_d);
			ENSURE_NEAR(D_fused[k], D_ref[k], 1e-13 * scale_d);
		}
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	return 0;
}

// The product from the records against a central difference of the forces along the direction
// itself: (f(x + h dx, v + h dv) - f(x - h dx, v - h dv)) / 2h. Each spring sees a relative
// displacement of at most 2 sqrt(3) per unit h, which multiplies the single-column truncation
// error of the header (2e-8) by at most 3.5^3 ~ 43 per spring, and a particle has a few springs:
// ~ 5e-6 absolute. The product is bounded by dim times the largest Jacobian entry (>= 1), so
// 1e-6 of that (>= 2.7e-5) leaves a margin of ~5, while a missing term of O(1..100) fails.
// The definite variant is checked against the dense matrix applied to the vectors (rounding
// only: 1e-12 of the same bound).
static int test_fused_product_matches_finite_differences(void)
{
	rng r = {1357};
	enum { N = 9 };
	const size_t dim = 3 * N;
	double x[3 * N], v[3 * N], dx[3 * N], dv[3 * N], out[3 * N], f[3 * N], fp[3 * N], fm[3 * N];
	double xp[3 * N], vp[3 * N], xm[3 * N], vm[3 * N];
	double* dfdx = malloc(dim * dim * sizeof(double));
	double* dfdv = malloc(dim * dim * sizeof(double));
	ENSURE(dfdx != NULL && dfdv != NULL);
	for (int trial = 0; trial < 10; trial++) {
		sm_model* m = random_model(&r, N, 20, trial % 2, x, v);
		ENSURE(m != NULL);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		for (size_t k = 0; k < dim; k++) {
			dx[k] = rng_uniform(&r, -1, 1);
			dv[k] = rng_uniform(&r, -1, 1);
		}
		for (int variant = 0; variant < 2; variant++) {
			ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
			              SM_OK);
			sm_model_jacobian_dense(m, x, v, (sm_jacobian_variant)variant, dfdx, dfdv);
			const double bound = fmax(max_abs(dfdx, dim * dim), max_abs(dfdv, dim * dim)) * (double)dim;
			for (int which = 0; which < 3; which++) {  // both, dx only, dv only
				const double* px = which == 2 ? NULL : dx;
				const double* pv = which == 1 ? NULL : dv;
				ENSURE_STATUS(sm_spring_jacobians_product(sj, m, px, pv, out), SM_OK);
				if (variant == SM_JACOBIAN_EXACT) {
					for (size_t k = 0; k < dim; k++) {
						xp[k] = x[k] + (px ? FD_STEP * px[k] : 0.0);
						xm[k] = x[k] - (px ? FD_STEP * px[k] : 0.0);
						vp[k] = v[k] + (pv ? FD_STEP * pv[k] : 0.0);
						vm[k] = v[k] - (pv ? FD_STEP * pv[k] : 0.0);
					}
					sm_model_forces(m, xp, vp, NULL, fp);
					sm_model_forces(m, xm, vm, NULL, fm);
					for (size_t k = 0; k < dim; k++)
						ENSURE_NEAR(out[k], (fp[k] - fm[k]) / (2.0 * FD_STEP), FD_RELATIVE * bound);
				} else {
					for (size_t i = 0; i < dim; i++) {
						double expect = 0.0;
						for (size_t j = 0; j < dim; j++)
							expect += (px ? dfdx[i * dim + j] * px[j] : 0.0) +
							          (pv ? dfdv[i * dim + j] * pv[j] : 0.0);
						ENSURE_NEAR(out[i], expect, 1e-12 * bound);
					}
				}
			}
		}
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	free(dfdx);
	free(dfdv);
	return 0;
}

// (a df/dx + b df/dv) p from the records of both variants against the dense matrices (dfdx and
// dfdv: room for (3n)^2 each), for pure stiffness, gamma-like scales and pure damping: equal to
// 1e-12 of the largest term times the dimension (a few rounding errors, with a margin).
static int combined_products_match_dense(const sm_model* m, sm_spring_jacobians* sj, const double* x,
                                         const double* v, const double* p, double* dfdx, double* dfdv)
{
	const size_t dim = 3 * (size_t)sm_model_particle_count(m);
	double* f = malloc(2 * dim * sizeof(double));
	ENSURE(f != NULL);
	double* out = f + dim;
	const double scales[3][2] = {{1.0, 0.0}, {2.5e-7, 5e-4}, {0.0, 1.0}};
	for (int variant = 0; variant < 2; variant++) {
		ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
		              SM_OK);
		ENSURE_STATUS(sm_model_jacobian_dense(m, x, v, (sm_jacobian_variant)variant, dfdx, dfdv), SM_OK);
		for (int s = 0; s < 3; s++) {
			const double a = scales[s][0], b = scales[s][1];
			ENSURE_STATUS(sm_spring_jacobians_combined_product(sj, m, a, b, p, out), SM_OK);
			const double bound =
			    fmax(a * max_abs(dfdx, dim * dim), b * max_abs(dfdv, dim * dim)) * (double)dim;
			for (size_t i = 0; i < dim; i++) {
				double expect = 0.0;
				for (size_t j = 0; j < dim; j++)
					expect += (a * dfdx[i * dim + j] + b * dfdv[i * dim + j]) * p[j];
				ENSURE_NEAR(out[i], expect, 1e-12 * bound);
			}
		}
	}
	free(f);
	return 0;
}

// The combined product (scale_k K + scale_d D) p against the dense matrices (built from
// sm_model_spring_jacobian's blocks, an independent expansion), both variants, with mass damping
// and gamma-like scales: equal to 1e-12 of the largest term (a few rounding errors, with a margin).
static int test_combined_product_matches_dense(void)
{
	rng r = {2468};
	enum { N = 9 };
	const size_t dim = 3 * N;
	double x[3 * N], v[3 * N], p[3 * N], out[3 * N];
	double* dfdx = malloc(dim * dim * sizeof(double));
	double* dfdv = malloc(dim * dim * sizeof(double));
	ENSURE(dfdx != NULL && dfdv != NULL);
	for (int trial = 0; trial < 10; trial++) {
		sm_model* m = random_model(&r, N, 20, trial % 2, x, v);
		ENSURE(m != NULL);
		sm_model_def md = sm_model_get_def(m);
		md.mass_damping = 0.5 * (double)(trial % 3);
		ENSURE_STATUS(sm_model_set_def(m, &md), SM_OK);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		for (size_t k = 0; k < dim; k++)
			p[k] = rng_uniform(&r, -1, 1);
		ENSURE(combined_products_match_dense(m, sj, x, v, p, dfdx, dfdv) == 0);
		ENSURE_STATUS(sm_spring_jacobians_combined_product(sj, m, 1.0, 1.0, NULL, out),
		              SM_ERROR_INVALID_ARGUMENT);
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	free(dfdx);
	free(dfdv);
	return 0;
}

// The sparse matrices filled from the records against central finite differences over the free
// degrees of freedom (exact variant, tolerance of the header), and, for both variants, against
// the dense matrices (built from sm_model_spring_jacobian's blocks, an independent expansion of
// the same few terms: equal to 1e-12 of the largest entry, a few rounding errors with a margin);
// sm_sparse_jacobian_fill gives the same numbers.
static int test_fill_from_springs_matches_finite_differences(void)
{
	rng r = {97531};
	enum { N = 10 };
	double x[3 * N], v[3 * N], f[3 * N], col[3 * N];
	for (int trial = 0; trial < 6; trial++) {
		sm_model* m = random_model(&r, N, 18, 1, x, v);
		ENSURE(m != NULL);
		sm_spring_def d = sm_default_spring_def();  // a duplicate pair and a second fixed particle
		d.a = 1;
		d.b = 0;
		d.stiffness = 33.0;
		d.damping = 0.4;
		ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		ENSURE_STATUS(sm_model_set_particle_motion(m, 5, SM_PARTICLE_FIXED), SM_OK);
		v[15] = v[16] = v[17] = 0.0;
		sm_sparse_jacobian* J = sm_sparse_jacobian_create(m);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(J != NULL && sj != NULL);
		const int64_t dim = sm_sparse_jacobian_dimension(J), nnz = sm_sparse_jacobian_nonzeros(J);
		const int64_t* rows = sm_sparse_jacobian_row_pointers(J);
		const int64_t* cols = sm_sparse_jacobian_column_indices(J);
		double* sx = malloc((size_t)nnz * sizeof(double));
		double* sv = malloc((size_t)nnz * sizeof(double));
		double* rx = malloc((size_t)nnz * sizeof(double));
		double* rv = malloc((size_t)nnz * sizeof(double));
		double* ax = malloc((size_t)(dim * dim) * sizeof(double));
		double* av = malloc((size_t)(dim * dim) * sizeof(double));
		ENSURE(sx && sv && rx && rv && ax && av);
		for (int variant = 0; variant < 2; variant++) {
			ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
			              SM_OK);
			ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, sx, sv), SM_OK);
			ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, (sm_jacobian_variant)variant, rx, rv), SM_OK);
			for (int64_t k = 0; k < nnz; k++)
				ENSURE(sx[k] == rx[k] && sv[k] == rv[k]);
			// Against the dense matrices over the free degrees of freedom.
			const size_t full = 3 * (size_t)N;
			double* dx_dense = malloc(full * full * sizeof(double));
			double* dv_dense = malloc(full * full * sizeof(double));
			ENSURE(dx_dense != NULL && dv_dense != NULL);
			sm_model_jacobian_dense(m, x, v, (sm_jacobian_variant)variant, dx_dense, dv_dense);
			csr_to_dense(dim, rows, cols, sx, ax);
			csr_to_dense(dim, rows, cols, sv, av);
			const double scale_x = max_abs(dx_dense, full * full), scale_v = max_abs(dv_dense, full * full);
			for (int32_t p = 0; p < N; p++)
				for (int32_t q = 0; q < N; q++) {
					const int32_t fp = sm_model_free_index(m, p), fq = sm_model_free_index(m, q);
					if (fp < 0 || fq < 0)
						continue;
					for (int i = 0; i < 3; i++)
						for (int j = 0; j < 3; j++) {
							const size_t dense = (3 * (size_t)p + i) * full + 3 * (size_t)q + j;
							const int64_t sparse = (3 * fp + i) * dim + 3 * fq + j;
							ENSURE_NEAR(ax[sparse], dx_dense[dense], 1e-12 * scale_x);
							ENSURE_NEAR(av[sparse], dv_dense[dense], 1e-12 * scale_v);
						}
				}
			free(dx_dense);
			free(dv_dense);
			// One matrix at a time gives the same values, written over NaN (rx and rv hold them
			// already from sm_sparse_jacobian_fill, so that a call leaving its output untouched
			// would pass unseen).
			for (int64_t k = 0; k < nnz; k++)
				rx[k] = rv[k] = NAN;
			ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, rx, NULL), SM_OK);
			ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, NULL, rv), SM_OK);
			for (int64_t k = 0; k < nnz; k++)
				ENSURE(rx[k] == sx[k] && rv[k] == sv[k]);
		}
		ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_OK);
		ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, sx, sv), SM_OK);
		csr_to_dense(dim, rows, cols, sx, ax);
		csr_to_dense(dim, rows, cols, sv, av);
		const double scale_x = max_abs(ax, (size_t)(dim * dim)), scale_v = max_abs(av, (size_t)(dim * dim));
		for (int32_t q = 0; q < N; q++) {
			const int32_t fq = sm_model_free_index(m, q);
			if (fq < 0)
				continue;
			for (int c = 0; c < 3; c++)
				for (int wrt = 0; wrt < 2; wrt++) {
					fd_column(m, x, v, wrt, 3 * (size_t)q + c, col);
					const double* a = wrt ? av : ax;
					for (int32_t p = 0; p < N; p++) {
						const int32_t fp = sm_model_free_index(m, p);
						if (fp < 0)
							continue;
						for (int i = 0; i < 3; i++)
							ENSURE_NEAR(a[(3 * fp + i) * dim + 3 * fq + c], col[3 * p + i],
							            FD_RELATIVE * (wrt ? scale_v : scale_x));
					}
				}
		}
		free(sx);
		free(sv);
		free(rx);
		free(rv);
		free(ax);
		free(av);
		sm_spring_jacobians_destroy(sj);
		sm_sparse_jacobian_destroy(J);
		sm_model_destroy(m);
	}
	return 0;
}

// At L = 0 the records give the documented blocks, ks I and D = 0, for both kinds and variants;
// a disabled spring gives zero blocks.
static int test_fused_degenerate_and_disabled_springs(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* m = sm_model_create(&md, NULL);
	ENSURE(m != NULL);
	sm_particle_def p = sm_default_particle_def();
	p.position[0] = 0.3;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	p.position[0] = 1.0;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 1;
	d.rest_length = 0.5;
	d.stiffness = 10.0;
	d.damping = 2.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	d.kind = SM_SPRING_ZERO_LENGTH;
	d.rest_length = 0.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	d.kind = SM_SPRING_REST_LENGTH;
	d.b = 2;
	d.rest_length = 0.4;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 2, false), SM_OK);
	const double x[9] = {0.3, 0, 0, 0.3, 0, 0, 1.0, 0.2, 0}, v[9] = {1, 2, 3, -1, 0, 4, 0, 1, 0};
	double f[9], K[9], D[9];
	sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
	ENSURE(sj != NULL);
	for (int variant = 0; variant < 2; variant++) {
		ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
		              SM_OK);
		for (int k = 0; k < 9; k++)
			ENSURE(isfinite(f[k]));
		for (int32_t s = 0; s < 3; s++) {
			ENSURE_STATUS(sm_spring_jacobians_block(sj, s, K, D), SM_OK);
			for (int k = 0; k < 9; k++) {
				ENSURE(K[k] == (s < 2 && k % 4 == 0 ? 10.0 : 0.0));
				ENSURE(D[k] == 0.0);
			}
		}
	}
	sm_spring_jacobians_destroy(sj);
	sm_model_destroy(m);
	return 0;
}

// Springs are evaluated four or two at a time where the processor allows it (forces.c), the last
// few alone. All must be the same IEEE operations: the forces of a model equal, bit for bit, its
// body forces plus each spring's force evaluated alone (a two-particle model, in spring order),
// and so do the stored Jacobian records, for both variants. The model includes a spring whose
// ends coincide (degenerate), a disabled one and springs sharing particles within a pair.
static int test_springs_in_groups_equal_springs_alone_bit_for_bit(void)
{
	rng r = {6060};
	enum { N = 9, S = 21 };
	double x[3 * N], v[3 * N], f[3 * N], expect[3 * N], fa[6], x2[6], v2[6];
	for (int trial = 0; trial < 4; trial++) {
		sm_model* m = random_model(&r, N, S, trial % 2, x, v);
		ENSURE(m != NULL);
		ENSURE_STATUS(add_degenerate_and_disabled_springs(m, x), SM_OK);
		const int32_t springs = sm_model_spring_count(m);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		for (int variant = 0; variant < 2; variant++) {
			ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)variant, f, sj),
			              SM_OK);
			// Body forces alone: the same model with every spring disabled (zero constants).
			sm_model* body = sm_model_clone(m);
			ENSURE(body != NULL);
			for (int32_t s = 0; s < springs; s++)
				ENSURE_STATUS(sm_model_set_spring_enabled(body, s, false), SM_OK);
			sm_model_forces(body, x, v, NULL, expect);
			sm_model_destroy(body);
			for (int32_t s = 0; s < springs; s++) {
				sm_spring_def def;
				ENSURE_STATUS(sm_model_get_spring(m, s, &def), SM_OK);
				sm_model* one = single_spring(m, s, x, v, x2, v2);
				ENSURE(one != NULL);
				if (!sm_model_spring_enabled(m, s))
					ENSURE_STATUS(sm_model_set_spring_enabled(one, 0, false), SM_OK);
				sm_spring_jacobians* alone = sm_spring_jacobians_create(one);
				ENSURE(alone != NULL);
				ENSURE_STATUS(
				    sm_model_forces_and_jacobians(one, x2, v2, NULL, (sm_jacobian_variant)variant, fa, alone),
				    SM_OK);
				for (int k = 0; k < 3; k++) {
					expect[3 * def.a + k] += fa[k];
					expect[3 * def.b + k] -= fa[k];
				}
				double K[9], D[9], K1[9], D1[9];
				ENSURE_STATUS(sm_spring_jacobians_block(sj, s, K, D), SM_OK);
				ENSURE_STATUS(sm_spring_jacobians_block(alone, 0, K1, D1), SM_OK);
				for (int k = 0; k < 9; k++)
					ENSURE(K[k] == K1[k] && D[k] == D1[k]);
				sm_spring_jacobians_destroy(alone);
				sm_model_destroy(one);
			}
			for (size_t k = 0; k < 3 * N; k++)
				ENSURE(f[k] == expect[k]);
		}
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	return 0;
}

// Misuse is an error, never a crash, and leaves the outputs untouched.
static int test_fused_errors(void)
{
	rng r = {11};
	double x[3 * 5], v[3 * 5], f[3 * 5], out[3 * 5], K[9];
	sm_model* m = random_model(&r, 5, 6, 0, x, v);
	ENSURE(m != NULL);
	sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
	ENSURE(sj != NULL);
	ENSURE(sm_spring_jacobians_create(NULL) == NULL);
	sm_spring_jacobians_destroy(NULL);
	// Nothing evaluated yet.
	ENSURE_STATUS(sm_spring_jacobians_block(sj, 0, K, NULL), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_spring_jacobians_product(sj, m, x, v, out), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_forces_and_jacobians(NULL, x, v, NULL, SM_JACOBIAN_EXACT, f, sj),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, NULL, v, NULL, SM_JACOBIAN_EXACT, f, sj),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, NULL),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, (sm_jacobian_variant)7, f, sj),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_OK);
	ENSURE_STATUS(sm_spring_jacobians_block(sj, 6, K, NULL), SM_ERROR_SPRING_INDEX);
	ENSURE_STATUS(sm_spring_jacobians_block(sj, -1, K, NULL), SM_ERROR_SPRING_INDEX);
	ENSURE_STATUS(sm_spring_jacobians_product(sj, NULL, x, v, out), SM_ERROR_INVALID_ARGUMENT);
	// Every function that takes a variant refuses one it does not know (the dense one built a
	// hybrid of both, the product took it for the exact one), writing nothing.
	double dense[15 * 15];
	for (int k = 0; k < 15; k++)
		out[k] = dense[k] = 42.0;
	const sm_jacobian_variant unknown = (sm_jacobian_variant)2;
	ENSURE_STATUS(sm_model_jacobian_dense(m, x, v, unknown, dense, NULL), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, unknown, x, v, out), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_spring_jacobian(m, 0, x, v, unknown, K, NULL), SM_ERROR_INVALID_ARGUMENT);
	for (int k = 0; k < 15; k++)
		ENSURE(out[k] == 42.0 && dense[k] == 42.0);
	ENSURE_STATUS(sm_model_jacobian_dense(NULL, x, v, SM_JACOBIAN_EXACT, dense, NULL),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, SM_JACOBIAN_EXACT, x, v, NULL),
	              SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_jacobian_dense(m, x, v, SM_JACOBIAN_DEFINITE, dense, NULL), SM_OK);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, SM_JACOBIAN_DEFINITE, x, v, out), SM_OK);
	// A model with another spring count no longer matches the storage.
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 1;
	d.stiffness = 5.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	for (int k = 0; k < 15; k++)
		f[k] = out[k] = 42.0;
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_ERROR_TOPOLOGY);
	ENSURE_STATUS(sm_spring_jacobians_product(sj, m, x, v, out), SM_ERROR_TOPOLOGY);
	for (int k = 0; k < 15; k++)
		ENSURE(f[k] == 42.0 && out[k] == 42.0);
	sm_sparse_jacobian* J = sm_sparse_jacobian_create(m);
	ENSURE(J != NULL);
	double values[1024];
	ENSURE((size_t)sm_sparse_jacobian_nonzeros(J) <= sizeof values / sizeof values[0]);
	ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, values, NULL), SM_ERROR_TOPOLOGY);
	ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, NULL, values, NULL), SM_ERROR_INVALID_ARGUMENT);
	sm_sparse_jacobian_destroy(J);
	sm_spring_jacobians_destroy(sj);
	sm_model_destroy(m);
	return 0;
}

// The Jacobian-vector products are not formed in place (model.h): an output that is one of the
// inputs, as in p = J p, is refused with nothing written, where the springs read entries that
// the mass-damping term had already overwritten.
static int test_products_refuse_an_output_that_is_an_input(void)
{
	rng r = {12};
	enum { N = 6 };
	double x[3 * N], v[3 * N], f[3 * N], p[3 * N], kept[3 * N];
	sm_model* m = random_model(&r, N, 8, 1, x, v);
	ENSURE(m != NULL);
	sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
	ENSURE(sj != NULL);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_OK);
	for (int k = 0; k < 3 * N; k++)
		kept[k] = rng_uniform(&r, -1, 1);
	const sm_jacobian_variant exact = SM_JACOBIAN_EXACT;
	memcpy(p, kept, sizeof p);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, exact, p, NULL, p), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, exact, NULL, p, p), SM_ERROR_INVALID_ARGUMENT);
	memcpy(p, kept, sizeof p);
	ENSURE_STATUS(sm_spring_jacobians_product(sj, m, p, NULL, p), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_spring_jacobians_product(sj, m, NULL, p, p), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_spring_jacobians_combined_product(sj, m, 0.25, 0.5, p, p), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(memcmp(p, kept, sizeof p) == 0);
	// Positions and velocities given as the output are refused too, and stay as they were.
	double xc[3 * N], vc[3 * N];
	memcpy(xc, x, sizeof x);
	memcpy(vc, v, sizeof v);
	ENSURE_STATUS(sm_model_jacobian_product(m, xc, v, exact, kept, NULL, xc), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_jacobian_product(m, x, vc, exact, kept, NULL, vc), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(memcmp(xc, x, sizeof x) == 0 && memcmp(vc, v, sizeof v) == 0);
	sm_spring_jacobians_destroy(sj);
	sm_model_destroy(m);
	return 0;
}

// The pattern belongs to the particles' motions and the springs' endpoints it was built from
// (model.h). A model in which a constrained and a free particle swapped motions, or a spring was
// moved to another particle at either end, keeps its counts but has another matrix: both fills
// must refuse it with SM_ERROR_TOPOLOGY and leave the values untouched. Undoing the change makes
// the pattern valid again.
static int test_sparse_jacobian_rejects_changed_motions_and_endpoints(void)
{
	rng r = {8642};
	enum { N = 8 };
	double x[3 * N], v[3 * N], f[3 * N];
	sm_model* m = random_model(&r, N, 14, 1, x, v);  // particle N - 1 fixed
	ENSURE(m != NULL);
	ENSURE_STATUS(sm_model_set_particle_motion(m, 2, SM_PARTICLE_DRIVEN), SM_OK);
	v[6] = v[7] = v[8] = 0.0;
	sm_sparse_jacobian* J = sm_sparse_jacobian_create(m);
	sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
	ENSURE(J != NULL && sj != NULL);
	const int64_t nnz = sm_sparse_jacobian_nonzeros(J);
	double* values = malloc((size_t)nnz * sizeof(double));
	ENSURE(values != NULL);
	ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, values, NULL), SM_OK);
	const int32_t moved = 5;
	sm_spring_def original;
	ENSURE_STATUS(sm_model_get_spring(m, moved, &original), SM_OK);
	int32_t other = 0;  // a particle that is neither end of the moved spring
	while (other == original.a || other == original.b)
		other++;
	for (int change = 0; change < 3; change++) {
		sm_spring_def d = original;
		if (change == 0) {  // particle 2 free, particle 4 driven: the same number of free particles
			ENSURE_STATUS(sm_model_set_particle_motion(m, 2, SM_PARTICLE_FREE), SM_OK);
			ENSURE_STATUS(sm_model_set_particle_motion(m, 4, SM_PARTICLE_DRIVEN), SM_OK);
		} else {
			if (change == 1)
				d.b = other;
			else
				d.a = other;
			ENSURE_STATUS(sm_model_set_spring(m, moved, &d), SM_OK);
		}
		ENSURE(sm_model_free_count(m) == N - 2 && sm_model_spring_count(m) == 14);
		for (int64_t k = 0; k < nnz; k++)
			values[k] = 42.0;
		ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, values, NULL),
		              SM_ERROR_TOPOLOGY);
		ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_EXACT, f, sj), SM_OK);
		ENSURE_STATUS(sm_sparse_jacobian_fill_from_springs(J, m, sj, values, NULL), SM_ERROR_TOPOLOGY);
		for (int64_t k = 0; k < nnz; k++)
			ENSURE(values[k] == 42.0);
		if (change == 0) {
			ENSURE_STATUS(sm_model_set_particle_motion(m, 4, SM_PARTICLE_FREE), SM_OK);
			ENSURE_STATUS(sm_model_set_particle_motion(m, 2, SM_PARTICLE_DRIVEN), SM_OK);
		} else {
			ENSURE_STATUS(sm_model_set_spring(m, moved, &original), SM_OK);
		}
		ENSURE_STATUS(sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, values, NULL), SM_OK);
	}
	free(values);
	sm_spring_jacobians_destroy(sj);
	sm_sparse_jacobian_destroy(J);
	sm_model_destroy(m);
	return 0;
}

// The combined product of models with a single spring (the smallest case of its running sum per
// first particle), with the spring's first particle not particle 0, and with mass damping, against
// the dense matrices; same tolerance argument as test_combined_product_matches_dense.
static int test_combined_product_of_a_single_spring(void)
{
	enum { N = 3 };
	double x[3 * N] = {0.1, 0.2, 0.3, 0.9, -0.4, 0.5, -0.3, 0.8, 0.2};
	double v[3 * N] = {0.5, -1.0, 0.25, -0.75, 0.6, 1.2, 0.3, -0.2, 0.9};
	double p[3 * N] = {0.4, -0.7, 0.2, 0.9, 0.1, -0.5, -0.3, 0.6, 0.8};
	double dfdx[3 * N * 3 * N], dfdv[3 * N * 3 * N];
	for (int ends = 0; ends < 2; ends++) {
		sm_model_def md = sm_default_model_def();
		md.mass_damping = 0.6;
		sm_model* m = sm_model_create(&md, NULL);
		ENSURE(m != NULL);
		for (int i = 0; i < N; i++) {
			sm_particle_def pd = sm_default_particle_def();
			pd.mass = 0.5 + i;
			ENSURE_STATUS(sm_model_add_particle(m, &pd, NULL), SM_OK);
		}
		sm_spring_def d = sm_default_spring_def();
		d.a = ends == 0 ? 0 : 2;
		d.b = 1;
		d.rest_length = 0.7;
		d.stiffness = 80.0;
		d.damping = 1.5;
		ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		sm_spring_jacobians* sj = sm_spring_jacobians_create(m);
		ENSURE(sj != NULL);
		ENSURE(combined_products_match_dense(m, sj, x, v, p, dfdx, dfdv) == 0);
		sm_spring_jacobians_destroy(sj);
		sm_model_destroy(m);
	}
	return 0;
}

// A NULL destination is refused like a NULL or unknown name (model.h), as
// sm_linear_solver_from_name refuses one, instead of being written through.
static int test_variant_from_name_refuses_null(void)
{
	ENSURE_STATUS(sm_jacobian_variant_from_name("exact", NULL), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_jacobian_variant_from_name("definite", NULL), SM_ERROR_INVALID_ARGUMENT);
	sm_jacobian_variant variant = SM_JACOBIAN_DEFINITE;
	ENSURE_STATUS(sm_jacobian_variant_from_name(NULL, &variant), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(variant == SM_JACOBIAN_DEFINITE);
	return 0;
}

// From mutation testing: the definiteness-preserving variant clamps the transverse stiffness
// ks (1 - l0/L) of a compressed spring at zero however slight the compression (law_rest_length.h),
// in the product of jacobian.c as in the stored records. A spring compressed to L = (1 - 1e-6) l0 along
// (1, 2, 2)/3, its far end moved across it by (2, -1, 0): the definite product is zero, the exact
// one the negative stiffness ks (1 - l0/L) times the move, on a and opposite on b. A clamp that
// began at 1 - l0/L < -1e-3 went unnoticed by the tests of the physics core (their random models
// compress their springs further).
// Tolerances: zero up to the rounding of u . r, a few ulps of ks |r| (1e-14 ks |r| allowed, where
// the missing clamp gives 1e-6 ks |r|); the exact product to 1e-9 of its size, 1 - l0/L = -1e-6
// being computed from a length that carries about 1e-16 relative error.
static int test_definite_product_clamps_a_slight_compression(void)
{
	const sm_model_def md = sm_default_model_def();  // gravity has no derivative
	sm_model* m = sm_model_create(&md, NULL);
	ENSURE(m != NULL);
	const double l0 = 1.5, ks = 60.0, shrink = 1.0 - 1e-6;
	const double scale = shrink * l0 / 3.0;  // d = scale (1, 2, 2), |d| = (1 - 1e-6) l0
	double x[6] = {0.1, 0.2, 0.3, 0.1 + scale, 0.2 + 2.0 * scale, 0.3 + 2.0 * scale};
	const double v[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
	for (int e = 0; e < 2; e++) {
		sm_particle_def p = sm_default_particle_def();
		for (int c = 0; c < 3; c++)
			p.position[c] = x[3 * e + c];
		ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	}
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 1;
	d.rest_length = l0;
	d.stiffness = ks;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	const double move[6] = {0.0, 0.0, 0.0, 2.0, -1.0, 0.0};  // across the spring: (1, 2, 2) . (2, -1, 0) = 0
	const double length =
	    sqrt((x[3] - x[0]) * (x[3] - x[0]) + (x[4] - x[1]) * (x[4] - x[1]) + (x[5] - x[2]) * (x[5] - x[2]));
	const double geometric = 1.0 - l0 / length;
	ENSURE(geometric < -0.9e-6 && geometric > -1.1e-6);
	const double bound = 1e-14 * ks * sqrt(5.0);
	double out[6], fused[6], f[6];
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, SM_JACOBIAN_DEFINITE, move, NULL, out), SM_OK);
	sm_spring_jacobians* records = sm_spring_jacobians_create(m);
	ENSURE(records != NULL);
	ENSURE_STATUS(sm_model_forces_and_jacobians(m, x, v, NULL, SM_JACOBIAN_DEFINITE, f, records), SM_OK);
	ENSURE_STATUS(sm_spring_jacobians_product(records, m, move, NULL, fused), SM_OK);
	for (int k = 0; k < 6; k++) {
		ENSURE_NEAR(out[k], 0.0, bound);
		ENSURE_NEAR(fused[k], 0.0, bound);
	}
	ENSURE_STATUS(sm_model_jacobian_product(m, x, v, SM_JACOBIAN_EXACT, move, NULL, out), SM_OK);
	const double allowed = 1e-9 * ks * fabs(geometric) * sqrt(5.0) + bound;
	for (int c = 0; c < 3; c++) {
		ENSURE_NEAR(out[c], ks * geometric * move[3 + c], allowed);
		ENSURE_NEAR(out[3 + c], -ks * geometric * move[3 + c], allowed);
	}
	sm_spring_jacobians_destroy(records);
	sm_model_destroy(m);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_spring_blocks_match_finite_differences);
	RUN_TEST(test_dense_jacobians_match_finite_differences);
	RUN_TEST(test_jacobian_product_matches_dense);
	RUN_TEST(test_sparse_jacobian_pattern_and_values);
	RUN_TEST(test_definite_variant_is_symmetric_negative_semidefinite);
	RUN_TEST(test_definite_equals_exact_for_stretched_springs_at_rest);
	RUN_TEST(test_degenerate_blocks_are_finite);
	RUN_TEST(test_disabled_spring_has_zero_blocks);
	RUN_TEST(test_fused_forces_equal_forces_exactly);
	RUN_TEST(test_fused_spring_blocks_match_finite_differences);
	RUN_TEST(test_spring_blocks_at_hard_states_match_the_closed_form);
	RUN_TEST(test_fused_product_matches_finite_differences);
	RUN_TEST(test_combined_product_matches_dense);
	RUN_TEST(test_combined_product_of_a_single_spring);
	RUN_TEST(test_variant_from_name_refuses_null);
	RUN_TEST(test_fill_from_springs_matches_finite_differences);
	RUN_TEST(test_fused_degenerate_and_disabled_springs);
	RUN_TEST(test_springs_in_groups_equal_springs_alone_bit_for_bit);
	RUN_TEST(test_fused_errors);
	RUN_TEST(test_products_refuse_an_output_that_is_an_input);
	RUN_TEST(test_sparse_jacobian_rejects_changed_motions_and_endpoints);
	RUN_TEST(test_definite_product_clamps_a_slight_compression);
	return TEST_SUMMARY();
}

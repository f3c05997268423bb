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
						expect[i] += (px ? dfdx[i * dim + j] * px[j] : 0.0) + (pv ? dfdv[i * dim + j] * pv[j] : 0.0);
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
		diff = fmax(diff, fabs(ke[k] - kd[k]));
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
	ENSURE_STATUS(sm_model_spring_jacobian(m, 4, x, v, SM_JACOBIAN_EXACT, K, D), SM_ERROR_SPRING_INDEX);
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
	return TEST_SUMMARY();
}

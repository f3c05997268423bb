// The vector operations of lib/vector_ops.c against SUNDIALS' own serial implementation: every
// operation on vectors of random values (lengths 0, 1, 7 and 1000; negative values, zeros of
// both signs), clones carrying the operations, and CVODE runs with and without them (BDF with
// the dense and the conjugate-gradient linear solvers, Adams with fixed-point iteration).
//
// Elementwise results must agree bit for bit. Sums may differ by rounding only: ours adds in
// four partial sums, SUNDIALS' serial vector in one running sum. Each ordering's error is at
// most (n - 1) u sum |terms| (u = 1.1e-16) and typically sqrt(n) u sum |terms|, about 4e-15 of
// the sum of magnitudes at n = 1000; sums are compared to a relative 1e-14 of that sum.
#include "physics_fixtures.h"
#include "simulation_internal.h"
#include "test_harness.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_pcg.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <stdbool.h>

// ---------------------------------------------------------------------------------------------
// Two sets of vectors holding the same values
// ---------------------------------------------------------------------------------------------

enum { VECTOR_COUNT = 6 };

static const sunindextype test_lengths[] = {0, 1, 7, 1000};
enum { LENGTH_COUNT = sizeof test_lengths / sizeof test_lengths[0] };

// `ours` carry the operations of vector_ops.c, `theirs` SUNDIALS' serial ones with the fused
// operations enabled (so that those are SUNDIALS' too, not its fallback of linear sums).
typedef struct vector_sets {
	SUNContext context;
	sunindextype length;
	N_Vector ours[VECTOR_COUNT];
	N_Vector theirs[VECTOR_COUNT];
	rng random;
} vector_sets;

static void sets_destroy(vector_sets* s)
{
	for (int k = 0; k < VECTOR_COUNT; k++) {
		N_VDestroy(s->ours[k]);
		N_VDestroy(s->theirs[k]);
	}
	if (s->context)
		SUNContext_Free(&s->context);
}

static bool sets_create(vector_sets* s, sunindextype n, uint64_t seed)
{
	*s = (vector_sets){.length = n, .random = {seed}};
	if (SUNContext_Create(SM_SUNDIALS_COMM_NULL, &s->context) != 0)
		return false;
	N_Vector model = N_VNew_Serial(n, s->context);
	if (!model)
		return false;
	sm_vector_ops_install(model);
	bool ok = true;
	for (int k = 0; k < VECTOR_COUNT; k++) {
		s->ours[k] = N_VClone(model);
		s->theirs[k] = N_VNew_Serial(n, s->context);
		ok = ok && s->ours[k] && s->theirs[k] && N_VEnableFusedOps_Serial(s->theirs[k], SUNTRUE) == 0;
	}
	N_VDestroy(model);
	return ok;
}

enum fill_kind {
	FILL_SIGNED,      // uniform in [-2, 2], one element in six +0 or -0
	FILL_NONZERO,     // uniform in [-2, -0.1] and [0.1, 2]
	FILL_POSITIVE,    // uniform in [0.1, 2] (weights)
	FILL_CONSTRAINT,  // constraint codes -2, -1, 0, 1, 2
	FILL_MASK,        // -1, 0 or 1 (a mask: positive means counted)
};

// The same values into vector k of both sets.
static void fill(vector_sets* s, int k, enum fill_kind kind)
{
	double* ours = N_VGetArrayPointer(s->ours[k]);
	double* theirs = N_VGetArrayPointer(s->theirs[k]);
	for (sunindextype i = 0; i < s->length; i++) {
		const double u = rng_uniform(&s->random, -1.0, 1.0);
		double v = 0.0;
		switch (kind) {
		case FILL_SIGNED:
			v = 2.0 * u;
			if (rng_uniform(&s->random, 0.0, 1.0) < 1.0 / 6.0)
				v = u < 0.0 ? -0.0 : 0.0;
			break;
		case FILL_NONZERO: v = u < 0.0 ? -0.1 + 1.9 * u : 0.1 + 1.9 * u; break;
		case FILL_POSITIVE: v = 0.1 + 1.9 * fabs(u); break;
		case FILL_CONSTRAINT: v = floor(2.5 * u + 2.5) - 2.0; break;
		case FILL_MASK: v = floor(1.5 * u + 1.5) - 1.0; break;
		}
		ours[i] = theirs[i] = v;
	}
}

// Vector k holds bit for bit the same elements in both sets.
static bool same_elements(const vector_sets* s, int k)
{
	if (s->length == 0)
		return true;
	return memcmp(N_VGetArrayPointer(s->ours[k]), N_VGetArrayPointer(s->theirs[k]),
	              (size_t)s->length * sizeof(double)) == 0;
}

// The same value bit for bit, or both NaN.
static bool same_value(double a, double b)
{
	return memcmp(&a, &b, sizeof a) == 0 || (isnan(a) && isnan(b));
}

// |a - b| <= 1e-14 magnitude, or both NaN.
#define ENSURE_SUM(a, b, magnitude)                                                                          \
	do {                                                                                                     \
		const double sa_ = (a), sb_ = (b);                                                                   \
		if (!(isnan(sa_) && isnan(sb_)))                                                                     \
			ENSURE_REL(sa_, sb_, 1e-14, (magnitude));                                                        \
	} while (0)

// sum |x_i y_i| over vectors i and j of `theirs` (y = NULL: sum |x_i|).
static double magnitude(const vector_sets* s, int i, int j)
{
	const double* x = N_VGetArrayPointer(s->theirs[i]);
	const double* y = j >= 0 ? N_VGetArrayPointer(s->theirs[j]) : NULL;
	double m = 0.0;
	for (sunindextype k = 0; k < s->length; k++)
		m += fabs(x[k] * (y ? y[k] : 1.0));
	return m;
}

// Runs a check on fresh sets of every test length (seeded with seed + the length's index).
static int for_each_length(int (*check)(vector_sets* s), uint64_t seed)
{
	for (int l = 0; l < LENGTH_COUNT; l++) {
		vector_sets s;
		if (!sets_create(&s, test_lengths[l], seed + (uint64_t)l)) {
			sets_destroy(&s);
			ENSURE(false);
		}
		const int failed = check(&s);
		sets_destroy(&s);
		if (failed) {
			printf("  at length %ld\n", (long)test_lengths[l]);
			return failed;
		}
	}
	return 0;
}

// test_NAME runs check_NAME on every length.
#define LENGTH_TEST(name, seed)                                                                              \
	static int test_##name(void)                                                                             \
	{                                                                                                        \
		return for_each_length(check_##name, seed);                                                          \
	}

// ---------------------------------------------------------------------------------------------
// Elementwise operations: bit for bit
// ---------------------------------------------------------------------------------------------

static int check_linear_sum(vector_sets* s)
{
	// The special cases +-1, equal and opposite weights, zero, and general weights.
	static const double weights[][2] = {{1, 1},      {1, -1},     {-1, 1},   {-1, -1},   {1, 0.3},
	                                    {-1, 0.3},   {0.3, 1},    {0.3, -1}, {0.7, 0.7}, {0.7, -0.7},
	                                    {-0.7, 0.7}, {0.3, -2.5}, {0, 0.5},  {0, 0},     {1e-3, 7}};
	for (size_t w = 0; w < sizeof weights / sizeof weights[0]; w++) {
		const double a = weights[w][0], b = weights[w][1];
		// z distinct, z = x, z = y, and x = y = z.
		static const int operands[][3] = {{0, 1, 2}, {0, 1, 0}, {0, 1, 1}, {0, 0, 0}};
		for (int c = 0; c < 4; c++) {
			const int x = operands[c][0], y = operands[c][1], z = operands[c][2];
			fill(s, 0, FILL_SIGNED);
			fill(s, 1, FILL_SIGNED);
			fill(s, 2, FILL_SIGNED);
			N_VLinearSum(a, s->ours[x], b, s->ours[y], s->ours[z]);
			N_VLinearSum(a, s->theirs[x], b, s->theirs[y], s->theirs[z]);
			if (!same_elements(s, z)) {
				printf("  a = %g, b = %g, operands %d %d %d\n", a, b, x, y, z);
				return 1;
			}
		}
	}
	return 0;
}

LENGTH_TEST(linear_sum, 11)

static int check_scale_and_constant(vector_sets* s)
{
	static const double factors[] = {1.0, -1.0, 0.0, 2.5, -0.3};
	for (size_t f = 0; f < sizeof factors / sizeof factors[0]; f++) {
		const double c = factors[f];
		fill(s, 0, FILL_SIGNED);
		fill(s, 1, FILL_SIGNED);
		N_VScale(c, s->ours[0], s->ours[1]);
		N_VScale(c, s->theirs[0], s->theirs[1]);
		ENSURE(same_elements(s, 1));
		N_VScale(c, s->ours[0], s->ours[0]);  // in place
		N_VScale(c, s->theirs[0], s->theirs[0]);
		ENSURE(same_elements(s, 0));
		N_VConst(c, s->ours[2]);
		N_VConst(c, s->theirs[2]);
		ENSURE(same_elements(s, 2));
		N_VAddConst(s->ours[1], c, s->ours[3]);
		N_VAddConst(s->theirs[1], c, s->theirs[3]);
		ENSURE(same_elements(s, 3));
		N_VCompare(fabs(c), s->ours[1], s->ours[4]);
		N_VCompare(fabs(c), s->theirs[1], s->theirs[4]);
		ENSURE(same_elements(s, 4));
	}
	return 0;
}

LENGTH_TEST(scale_and_constant, 21)

static int check_products_quotients_abs_inverse(vector_sets* s)
{
	fill(s, 0, FILL_SIGNED);
	fill(s, 1, FILL_NONZERO);
	N_VProd(s->ours[0], s->ours[1], s->ours[2]);
	N_VProd(s->theirs[0], s->theirs[1], s->theirs[2]);
	ENSURE(same_elements(s, 2));
	N_VDiv(s->ours[0], s->ours[1], s->ours[3]);
	N_VDiv(s->theirs[0], s->theirs[1], s->theirs[3]);
	ENSURE(same_elements(s, 3));
	N_VAbs(s->ours[0], s->ours[4]);
	N_VAbs(s->theirs[0], s->theirs[4]);
	ENSURE(same_elements(s, 4));
	N_VInv(s->ours[1], s->ours[5]);
	N_VInv(s->theirs[1], s->theirs[5]);
	ENSURE(same_elements(s, 5));
	N_VProd(s->ours[0], s->ours[1], s->ours[0]);  // in place
	N_VProd(s->theirs[0], s->theirs[1], s->theirs[0]);
	ENSURE(same_elements(s, 0));
	return 0;
}

LENGTH_TEST(products_quotients_abs_inverse, 31)

// Inversion with a test for zeros, constraint masks: the vectors and the answers.
static int check_inverse_test_and_constraints(vector_sets* s)
{
	for (int zeros = 0; zeros < 2; zeros++) {
		fill(s, 0, zeros ? FILL_SIGNED : FILL_NONZERO);
		fill(s, 1, FILL_SIGNED);  // what stands in z before
		ENSURE(N_VInvTest(s->ours[0], s->ours[1]) == N_VInvTest(s->theirs[0], s->theirs[1]));
		ENSURE(same_elements(s, 1));
		fill(s, 1, FILL_SIGNED);
		ENSURE(N_VInvTestLocal(s->ours[0], s->ours[1]) == N_VInvTestLocal(s->theirs[0], s->theirs[1]));
		ENSURE(same_elements(s, 1));
	}
	for (int trial = 0; trial < 3; trial++) {
		fill(s, 0, FILL_CONSTRAINT);
		fill(s, 1, trial == 0 ? FILL_POSITIVE : FILL_SIGNED);  // all hold in the first trial
		fill(s, 2, FILL_SIGNED);
		const sunbooleantype ours = N_VConstrMask(s->ours[0], s->ours[1], s->ours[2]);
		ENSURE(ours == N_VConstrMask(s->theirs[0], s->theirs[1], s->theirs[2]));
		ENSURE(same_elements(s, 2));
		ENSURE(N_VConstrMaskLocal(s->ours[0], s->ours[1], s->ours[2]) ==
		       N_VConstrMaskLocal(s->theirs[0], s->theirs[1], s->theirs[2]));
		ENSURE(same_elements(s, 2));
	}
	return 0;
}

LENGTH_TEST(inverse_test_and_constraints, 41)

// ---------------------------------------------------------------------------------------------
// Reductions
// ---------------------------------------------------------------------------------------------

// Extremes and minimum quotients are exact whatever the order.
static int check_extremes(vector_sets* s)
{
	fill(s, 0, FILL_SIGNED);
	fill(s, 1, FILL_SIGNED);  // denominators with zeros
	ENSURE(same_value(N_VMaxNorm(s->ours[0]), N_VMaxNorm(s->theirs[0])));
	ENSURE(same_value(N_VMaxNormLocal(s->ours[0]), N_VMaxNormLocal(s->theirs[0])));
	if (s->length > 0) {
		ENSURE(N_VMin(s->ours[0]) == N_VMin(s->theirs[0]));
		ENSURE(N_VMinLocal(s->ours[0]) == N_VMinLocal(s->theirs[0]));
	} else {
		// SUNDIALS' serial vector reads the first element of an empty vector; ours answers
		// like the minimum quotient over nothing.
		ENSURE(N_VMin(s->ours[0]) == SUN_BIG_REAL);
	}
	ENSURE(same_value(N_VMinQuotient(s->ours[0], s->ours[1]), N_VMinQuotient(s->theirs[0], s->theirs[1])));
	ENSURE(same_value(N_VMinQuotientLocal(s->ours[0], s->ours[1]),
	                  N_VMinQuotientLocal(s->theirs[0], s->theirs[1])));
	N_VConst(0.0, s->ours[1]);  // no quotient at all
	N_VConst(0.0, s->theirs[1]);
	ENSURE(N_VMinQuotient(s->ours[0], s->ours[1]) == SUN_BIG_REAL);
	ENSURE(N_VMinQuotient(s->theirs[0], s->theirs[1]) == SUN_BIG_REAL);
	return 0;
}

LENGTH_TEST(extremes, 51)

// Random values leave the extremes where the random numbers put them, which is at the first or
// last element only by chance: each element in turn holds the minimum, the largest magnitude and
// the smallest quotient (the others are 1, their quotients 1), so that a loop passing over any
// element (starting one late, ending one early) gives another answer.
static int check_extremes_at_every_position(vector_sets* s)
{
	for (sunindextype k = 0; k < s->length; k++) {
		N_VConst(1.0, s->ours[0]);
		N_VConst(1.0, s->theirs[0]);
		N_VConst(1.0, s->ours[1]);
		N_VConst(1.0, s->theirs[1]);
		N_VGetArrayPointer(s->ours[0])[k] = N_VGetArrayPointer(s->theirs[0])[k] = -3.0;
		N_VGetArrayPointer(s->ours[1])[k] = N_VGetArrayPointer(s->theirs[1])[k] = 0.5;
		ENSURE(N_VMin(s->ours[0]) == -3.0);
		ENSURE(N_VMin(s->theirs[0]) == -3.0);
		ENSURE(N_VMaxNorm(s->ours[0]) == 3.0);
		ENSURE(N_VMaxNorm(s->theirs[0]) == 3.0);
		ENSURE(N_VMinQuotient(s->ours[0], s->ours[1]) == -6.0);
		ENSURE(N_VMinQuotient(s->theirs[0], s->theirs[1]) == -6.0);
	}
	return 0;
}

LENGTH_TEST(extremes_at_every_position, 52)

static int check_sums_and_norms(vector_sets* s)
{
	fill(s, 0, FILL_SIGNED);
	fill(s, 1, FILL_SIGNED);
	fill(s, 2, FILL_POSITIVE);
	fill(s, 3, FILL_MASK);
	const double products = magnitude(s, 0, 1);
	ENSURE_SUM(N_VDotProd(s->ours[0], s->ours[1]), N_VDotProd(s->theirs[0], s->theirs[1]), products);
	ENSURE_SUM(N_VDotProdLocal(s->ours[0], s->ours[1]), N_VDotProdLocal(s->theirs[0], s->theirs[1]),
	           products);
	ENSURE_SUM(N_VL1Norm(s->ours[0]), N_VL1Norm(s->theirs[0]), 0.0);
	ENSURE_SUM(N_VL1NormLocal(s->ours[0]), N_VL1NormLocal(s->theirs[0]), 0.0);
	// Sums of squares have no cancellation: relative to the values themselves.
	ENSURE_SUM(N_VWSqrSumLocal(s->ours[0], s->ours[2]), N_VWSqrSumLocal(s->theirs[0], s->theirs[2]), 0.0);
	ENSURE_SUM(N_VWSqrSumMaskLocal(s->ours[0], s->ours[2], s->ours[3]),
	           N_VWSqrSumMaskLocal(s->theirs[0], s->theirs[2], s->theirs[3]), 0.0);
	ENSURE_SUM(N_VWrmsNorm(s->ours[0], s->ours[2]), N_VWrmsNorm(s->theirs[0], s->theirs[2]), 0.0);
	ENSURE_SUM(N_VWrmsNormMask(s->ours[0], s->ours[2], s->ours[3]),
	           N_VWrmsNormMask(s->theirs[0], s->theirs[2], s->theirs[3]), 0.0);
	ENSURE_SUM(N_VWL2Norm(s->ours[0], s->ours[2]), N_VWL2Norm(s->theirs[0], s->theirs[2]), 0.0);
	if (s->length == 0)  // the mean square of nothing is 0/0
		ENSURE(isnan(N_VWrmsNorm(s->ours[0], s->ours[2])));
	// A mask with no positive element.
	N_VConst(-1.0, s->ours[3]);
	N_VConst(-1.0, s->theirs[3]);
	ENSURE(same_value(N_VWrmsNormMask(s->ours[0], s->ours[2], s->ours[3]),
	                  N_VWrmsNormMask(s->theirs[0], s->theirs[2], s->theirs[3])));
	return 0;
}

LENGTH_TEST(sums_and_norms, 61)

// ---------------------------------------------------------------------------------------------
// Fused operations
// ---------------------------------------------------------------------------------------------

static int check_linear_combination(vector_sets* s)
{
	double c[VECTOR_COUNT];
	for (int nvec = 1; nvec < VECTOR_COUNT; nvec++)
		for (int in_place = 0; in_place < 2; in_place++)
			for (int unit_first = 0; unit_first < 2; unit_first++) {
				for (int k = 0; k < VECTOR_COUNT; k++) {
					fill(s, k, FILL_SIGNED);
					c[k] = rng_uniform(&s->random, -2.0, 2.0);
				}
				if (unit_first)  // z += sum_{j>0} c_j X_j when z = X[0]
					c[0] = 1.0;
				if (nvec == 2 && !unit_first)  // the equal-weights case of a linear sum
					c[1] = c[0];
				const int z = in_place ? 0 : VECTOR_COUNT - 1;
				ENSURE(N_VLinearCombination(nvec, c, s->ours, s->ours[z]) == 0);
				ENSURE(N_VLinearCombination(nvec, c, s->theirs, s->theirs[z]) == 0);
				ENSURE(same_elements(s, z));
			}
#if SUNDIALS_VERSION_MAJOR >= 7 && !defined(SUNDIALS_ENABLE_ERROR_CHECKS)
	// SUNDIALS 7 built without its error checks does not check nvec: ours return the code its checks do.
	ENSURE(N_VLinearCombination(0, c, s->ours, s->ours[0]) == SUN_ERR_ARG_OUTOFRANGE);
#else
	ENSURE(N_VLinearCombination(0, c, s->ours, s->ours[0]) ==
	       N_VLinearCombination(0, c, s->theirs, s->theirs[0]));
#endif
	return 0;
}

LENGTH_TEST(linear_combination, 71)

static int check_scale_add_multi_and_scale_array(vector_sets* s)
{
	double c[VECTOR_COUNT];
	N_Vector ours_y[2], ours_z[2], theirs_y[2], theirs_z[2];
	for (int nvec = 1; nvec <= 2; nvec++)
		for (int in_place = 0; in_place < 2; in_place++) {
			for (int k = 0; k < VECTOR_COUNT; k++) {
				fill(s, k, FILL_SIGNED);
				c[k] = k == 0 ? 1.0 : rng_uniform(&s->random, -2.0, 2.0);  // c_0 = 1: z = x + y
			}
			// x = vector 0, Y = vectors 1 and 2, Z = Y or vectors 3 and 4.
			for (int j = 0; j < nvec; j++) {
				ours_y[j] = s->ours[1 + j];
				theirs_y[j] = s->theirs[1 + j];
				ours_z[j] = in_place ? ours_y[j] : s->ours[3 + j];
				theirs_z[j] = in_place ? theirs_y[j] : s->theirs[3 + j];
			}
			ENSURE(N_VScaleAddMulti(nvec, c, s->ours[0], ours_y, ours_z) == 0);
			ENSURE(N_VScaleAddMulti(nvec, c, s->theirs[0], theirs_y, theirs_z) == 0);
			for (int k = 1; k < 5; k++)
				ENSURE(same_elements(s, k));
			ENSURE(N_VScaleVectorArray(nvec, c + 1, ours_y, ours_z) == 0);
			ENSURE(N_VScaleVectorArray(nvec, c + 1, theirs_y, theirs_z) == 0);
			for (int k = 1; k < 5; k++)
				ENSURE(same_elements(s, k));
		}
	return 0;
}

LENGTH_TEST(scale_add_multi_and_scale_array, 81)

static int check_dot_product_multi(vector_sets* s)
{
	double ours[VECTOR_COUNT], theirs[VECTOR_COUNT];
	for (int k = 0; k < VECTOR_COUNT; k++)
		fill(s, k, FILL_SIGNED);
	for (int nvec = 1; nvec < VECTOR_COUNT; nvec++) {
		ENSURE(N_VDotProdMulti(nvec, s->ours[0], s->ours + 1, ours) == 0);
		ENSURE(N_VDotProdMulti(nvec, s->theirs[0], s->theirs + 1, theirs) == 0);
		for (int j = 0; j < nvec; j++)
			ENSURE_SUM(ours[j], theirs[j], magnitude(s, 0, 1 + j));
		ENSURE(N_VDotProdMultiLocal(nvec, s->ours[0], s->ours + 1, ours) == 0);
		for (int j = 0; j < nvec; j++)
			ENSURE_SUM(ours[j], theirs[j], magnitude(s, 0, 1 + j));
	}
	return 0;
}

LENGTH_TEST(dot_product_multi, 91)

// The fused operations go through the vectors in blocks of 1024 elements (lib/vector_ops.c), so
// that a block of the output and one of an input stay in the L1 cache while several vectors are
// combined; the lengths above all fit in one block. At exactly one block, one element more, and
// two blocks and a part the results must still be SUNDIALS' bit for bit.
static int test_fused_operations_across_blocks(void)
{
	static const sunindextype lengths[] = {1024, 1025, 2 * 1024 + 37};
	for (size_t l = 0; l < sizeof lengths / sizeof lengths[0]; l++) {
		vector_sets s;
		if (!sets_create(&s, lengths[l], 101 + (uint64_t)l)) {
			sets_destroy(&s);
			ENSURE(false);
		}
		const int failed = check_linear_combination(&s) || check_scale_add_multi_and_scale_array(&s);
		sets_destroy(&s);
		if (failed) {
			printf("  at length %ld\n", (long)lengths[l]);
			return 1;
		}
	}
	return 0;
}

// ---------------------------------------------------------------------------------------------
// The table of operations and its clones
// ---------------------------------------------------------------------------------------------

static bool same_operations(N_Vector a, N_Vector b)
{
	return memcmp(a->ops, b->ops, sizeof *a->ops) == 0;
}

static int test_installed_operations_and_clones(void)
{
	SUNContext context;
	ENSURE(SUNContext_Create(SM_SUNDIALS_COMM_NULL, &context) == 0);
	N_Vector plain = N_VNew_Serial(5, context);
	N_Vector v = N_VNew_Serial(5, context);
	ENSURE(plain && v);
	sm_vector_ops_install(v);
	const N_Vector_Ops ours = v->ops, theirs = plain->ops;
#define ENSURE_REPLACED(op) ENSURE(ours->op != NULL && ours->op != theirs->op)
	ENSURE_REPLACED(nvlinearsum);
	ENSURE_REPLACED(nvconst);
	ENSURE_REPLACED(nvprod);
	ENSURE_REPLACED(nvdiv);
	ENSURE_REPLACED(nvscale);
	ENSURE_REPLACED(nvabs);
	ENSURE_REPLACED(nvinv);
	ENSURE_REPLACED(nvaddconst);
	ENSURE_REPLACED(nvdotprod);
	ENSURE_REPLACED(nvmaxnorm);
	ENSURE_REPLACED(nvwrmsnorm);
	ENSURE_REPLACED(nvwrmsnormmask);
	ENSURE_REPLACED(nvmin);
	ENSURE_REPLACED(nvwl2norm);
	ENSURE_REPLACED(nvl1norm);
	ENSURE_REPLACED(nvcompare);
	ENSURE_REPLACED(nvinvtest);
	ENSURE_REPLACED(nvconstrmask);
	ENSURE_REPLACED(nvminquotient);
	ENSURE_REPLACED(nvdotprodlocal);
	ENSURE_REPLACED(nvmaxnormlocal);
	ENSURE_REPLACED(nvminlocal);
	ENSURE_REPLACED(nvl1normlocal);
	ENSURE_REPLACED(nvinvtestlocal);
	ENSURE_REPLACED(nvconstrmasklocal);
	ENSURE_REPLACED(nvminquotientlocal);
	ENSURE_REPLACED(nvwsqrsumlocal);
	ENSURE_REPLACED(nvwsqrsummasklocal);
	ENSURE_REPLACED(nvdotprodmultilocal);
	ENSURE_REPLACED(nvlinearcombination);
	ENSURE_REPLACED(nvscaleaddmulti);
	ENSURE_REPLACED(nvdotprodmulti);
	ENSURE_REPLACED(nvscalevectorarray);
#undef ENSURE_REPLACED
	// Memory, identity and access stay SUNDIALS'.
	ENSURE(ours->nvclone == theirs->nvclone && ours->nvcloneempty == theirs->nvcloneempty);
	ENSURE(ours->nvdestroy == theirs->nvdestroy && ours->nvgetarraypointer == theirs->nvgetarraypointer);
	ENSURE(ours->nvgetvectorid == theirs->nvgetvectorid && ours->nvgetlength == theirs->nvgetlength);

	N_Vector clone = N_VClone(v);
	N_Vector empty = N_VCloneEmpty(v);
	N_Vector* array = N_VCloneVectorArray(3, v);
	N_Vector clone_of_clone = clone ? N_VClone(clone) : NULL;
	const bool all = clone && empty && array && clone_of_clone && same_operations(clone, v) &&
	                 same_operations(empty, v) && same_operations(array[0], v) &&
	                 same_operations(array[2], v) && same_operations(clone_of_clone, v);
	N_VDestroy(clone);
	N_VDestroy(empty);
	N_VDestroyVectorArray(array, 3);
	N_VDestroy(clone_of_clone);
	N_VDestroy(v);
	N_VDestroy(plain);
	SUNContext_Free(&context);
	ENSURE(all);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// CVODE with and without the operations: the heat equation
// ---------------------------------------------------------------------------------------------
//
// y_i' = D/h^2 (y_{i-1} - 2 y_i + y_{i+1}), i = 1..N, h = 1/(N + 1), y_0 = y_{N+1} = 0. The
// sine modes s_k,i = sin(k pi i h) are eigenvectors of the second difference with eigenvalues
// lambda_k = -(4 D/h^2) sin^2(k pi h / 2), so y(0) = s_1 + s_3 / 2 gives
// y(t) = exp(lambda_1 t) s_1 + exp(lambda_3 t) s_3 / 2. With D = 1 the problem is stiff
// (lambda_N / lambda_1 = 1560): BDF with the dense solver and with conjugate gradients
// (I - gamma J is symmetric positive definite). With D = 0.001, Adams with fixed-point iteration.

enum { HEAT_LENGTH = 61, HEAT_OUTPUTS = 8 };

typedef enum heat_setup { HEAT_BDF_DENSE, HEAT_BDF_PCG, HEAT_ADAMS_FIXED_POINT } heat_setup;

typedef struct heat {
	double rate;     // D/h^2 [1/s]
	double gamma;    // of the last preconditioner set-up [s]
	N_Vector model;  // the state vector given to CVodeInit: every vector must carry its operations
	int checked;     // vectors seen in the callbacks
	int foreign;     // of which with other operations
} heat;

typedef struct heat_run {
	double y[HEAT_OUTPUTS][HEAT_LENGTH];
	long steps;
	double error;  // max |y - closed form| over the outputs
	int checked;
	int foreign;
} heat_run;

static void check_vector(heat* h, N_Vector v)
{
	h->checked++;
	if (!same_operations(v, h->model))
		h->foreign++;
}

static int heat_rhs(sunrealtype t, N_Vector yv, N_Vector ydotv, void* user_data)
{
	(void)t;
	heat* h = user_data;
	check_vector(h, yv);
	check_vector(h, ydotv);
	const double* y = N_VGetArrayPointer(yv);
	double* ydot = N_VGetArrayPointer(ydotv);
	for (int i = 0; i < HEAT_LENGTH; i++) {
		const double left = i > 0 ? y[i - 1] : 0.0;
		const double right = i + 1 < HEAT_LENGTH ? y[i + 1] : 0.0;
		ydot[i] = h->rate * (left - 2.0 * y[i] + right);
	}
	return 0;
}

static int heat_jacobian(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data, N_Vector tmp1,
                         N_Vector tmp2, N_Vector tmp3)
{
	(void)t;
	heat* h = user_data;
	N_Vector vectors[] = {y, fy, tmp1, tmp2, tmp3};
	for (int k = 0; k < 5; k++)
		check_vector(h, vectors[k]);
	SUNMatZero(J);
	for (int i = 0; i < HEAT_LENGTH; i++) {
		SM_ELEMENT_D(J, i, i) = -2.0 * h->rate;
		if (i > 0)
			SM_ELEMENT_D(J, i, i - 1) = h->rate;
		if (i + 1 < HEAT_LENGTH)
			SM_ELEMENT_D(J, i, i + 1) = h->rate;
	}
	return 0;
}

// Jacobian-vector product J v: the right-hand side is linear.
static int heat_jacobian_times(N_Vector v, N_Vector Jv, sunrealtype t, N_Vector y, N_Vector fy,
                               void* user_data, N_Vector tmp)
{
	heat* h = user_data;
	check_vector(h, y);
	check_vector(h, fy);
	check_vector(h, tmp);
	return heat_rhs(t, v, Jv, user_data);
}

static int heat_preconditioner_setup(sunrealtype t, N_Vector y, N_Vector fy, sunbooleantype jok,
                                     sunbooleantype* jcur, sunrealtype gamma, void* user_data)
{
	(void)t;
	(void)jok;
	heat* h = user_data;
	check_vector(h, y);
	check_vector(h, fy);
	h->gamma = gamma;
	*jcur = SUNTRUE;
	return 0;
}

// The diagonal of I - gamma J: 1 + 2 gamma D/h^2.
static int heat_preconditioner_solve(sunrealtype t, N_Vector y, N_Vector fy, N_Vector r, N_Vector z,
                                     sunrealtype gamma, sunrealtype delta, int lr, void* user_data)
{
	(void)t;
	(void)gamma;
	(void)delta;
	(void)lr;
	heat* h = user_data;
	N_Vector vectors[] = {y, fy, r, z};
	for (int k = 0; k < 4; k++)
		check_vector(h, vectors[k]);
	N_VScale(1.0 / (1.0 + 2.0 * h->gamma * h->rate), r, z);
	return 0;
}

// Which operations the state vector carries.
typedef enum heat_operations {
	OPERATIONS_SUNDIALS,       // SUNDIALS' serial ones
	OPERATIONS_OURS,           // vector_ops.c
	OPERATIONS_OURS_BUT_SUMS,  // vector_ops.c, with SUNDIALS' sums and norms put back
} heat_operations;

// Puts SUNDIALS' sums (dot products, norms, sums of squares) back into v's operations.
static void restore_sundials_sums(N_Vector v, N_Vector plain)
{
	N_Vector_Ops ops = v->ops;
	const N_Vector_Ops theirs = plain->ops;
	ops->nvdotprod = theirs->nvdotprod;
	ops->nvwrmsnorm = theirs->nvwrmsnorm;
	ops->nvwrmsnormmask = theirs->nvwrmsnormmask;
	ops->nvwl2norm = theirs->nvwl2norm;
	ops->nvl1norm = theirs->nvl1norm;
	ops->nvdotprodlocal = theirs->nvdotprodlocal;
	ops->nvl1normlocal = theirs->nvl1normlocal;
	ops->nvwsqrsumlocal = theirs->nvwsqrsumlocal;
	ops->nvwsqrsummasklocal = theirs->nvwsqrsummasklocal;
	ops->nvdotprodmulti = theirs->nvdotprodmulti;
	ops->nvdotprodmultilocal = theirs->nvdotprodmultilocal;
}

static int run_heat(heat_setup setup, heat_operations operations, heat_run* out)
{
	const double pi = 3.14159265358979323846;
	const double step = 1.0 / (HEAT_LENGTH + 1);
	const double diffusion = setup == HEAT_ADAMS_FIXED_POINT ? 0.001 : 1.0;  // [m^2/s]
	const double t_end = setup == HEAT_ADAMS_FIXED_POINT ? 20.0 : 0.2;       // [s]
	heat h = {.rate = diffusion / (step * step)};
	SUNContext context = NULL;
	void* cvode = NULL;
	SUNMatrix matrix = NULL;
	SUNLinearSolver linear = NULL;
	SUNNonlinearSolver nonlinear = NULL;
	N_Vector y = NULL;
	int result = 1;
	if (SUNContext_Create(SM_SUNDIALS_COMM_NULL, &context) != 0 || !(y = N_VNew_Serial(HEAT_LENGTH, context)))
		goto done;
	if (operations != OPERATIONS_SUNDIALS)
		sm_vector_ops_install(y);
	if (operations == OPERATIONS_OURS_BUT_SUMS) {
		N_Vector plain = N_VNew_Serial(1, context);
		if (!plain)
			goto done;
		restore_sundials_sums(y, plain);
		N_VDestroy(plain);
	}
	h.model = y;
	double* yd = N_VGetArrayPointer(y);
	for (int i = 0; i < HEAT_LENGTH; i++)
		yd[i] = sin(pi * (i + 1) * step) + 0.5 * sin(3.0 * pi * (i + 1) * step);
	cvode = CVodeCreate(setup == HEAT_ADAMS_FIXED_POINT ? CV_ADAMS : CV_BDF, context);
	if (!cvode || CVodeInit(cvode, heat_rhs, 0.0, y) != CV_SUCCESS ||
	    CVodeSStolerances(cvode, 1e-8, 1e-10) != CV_SUCCESS || CVodeSetUserData(cvode, &h) != CV_SUCCESS ||
	    CVodeSetMaxNumSteps(cvode, 100000) != CV_SUCCESS)
		goto done;
	switch (setup) {
	case HEAT_BDF_DENSE:
		matrix = SUNDenseMatrix(HEAT_LENGTH, HEAT_LENGTH, context);
		linear = matrix ? SUNLinSol_Dense(y, matrix, context) : NULL;
		if (!linear || CVodeSetLinearSolver(cvode, linear, matrix) != CV_SUCCESS ||
		    CVodeSetJacFn(cvode, heat_jacobian) != CV_SUCCESS)
			goto done;
		break;
	case HEAT_BDF_PCG:
		linear = SUNLinSol_PCG(y, SUN_PREC_LEFT, 50, context);
		if (!linear || CVodeSetLinearSolver(cvode, linear, NULL) != CV_SUCCESS ||
		    CVodeSetJacTimes(cvode, NULL, heat_jacobian_times) != CV_SUCCESS ||
		    CVodeSetPreconditioner(cvode, heat_preconditioner_setup, heat_preconditioner_solve) != CV_SUCCESS)
			goto done;
		break;
	case HEAT_ADAMS_FIXED_POINT:
		nonlinear = SUNNonlinSol_FixedPoint(y, 0, context);
		if (!nonlinear || CVodeSetNonlinearSolver(cvode, nonlinear) != CV_SUCCESS)
			goto done;
		break;
	}
	N_Vector yout = N_VClone(y);
	if (!yout)
		goto done;
	out->error = 0.0;
	const double lambda1 = -4.0 * h.rate * pow(sin(pi * step / 2.0), 2);
	const double lambda3 = -4.0 * h.rate * pow(sin(3.0 * pi * step / 2.0), 2);
	int flag = CV_SUCCESS;
	for (int k = 0; k < HEAT_OUTPUTS && flag == CV_SUCCESS; k++) {
		const double t_out = t_end * (k + 1) / HEAT_OUTPUTS;
		double t;
		flag = CVode(cvode, t_out, yout, &t, CV_NORMAL);
		const double* yo = N_VGetArrayPointer(yout);
		for (int i = 0; i < HEAT_LENGTH; i++) {
			out->y[k][i] = yo[i];
			const double exact = exp(lambda1 * t) * sin(pi * (i + 1) * step) +
			                     0.5 * exp(lambda3 * t) * sin(3.0 * pi * (i + 1) * step);
			out->error = worst_of(out->error, fabs(yo[i] - exact));
		}
	}
	// CVODE's own vectors: the prediction, the current state, f(y) and the history column.
	double tcur, gamma, rl1;
	N_Vector ypred, yn, fn, zn1;
	void* data;
	if (flag == CV_SUCCESS && CVodeGetNonlinearSystemData(cvode, &tcur, &ypred, &yn, &fn, &gamma, &rl1, &zn1,
	                                                      &data) == CV_SUCCESS) {
		N_Vector vectors[] = {ypred, yn, fn, zn1, yout};
		for (int k = 0; k < 5; k++)
			check_vector(&h, vectors[k]);
		result = CVodeGetNumSteps(cvode, &out->steps) == CV_SUCCESS ? 0 : 1;
	}
	N_VDestroy(yout);
	out->checked = h.checked;
	out->foreign = h.foreign;

done:
	CVodeFree(&cvode);
	SUNLinSolFree(linear);
	SUNMatDestroy(matrix);
	if (nonlinear)
		SUNNonlinSolFree(nonlinear);
	N_VDestroy(y);
	if (context)
		SUNContext_Free(&context);
	return result;
}

static double largest_difference(const heat_run* a, const heat_run* b)
{
	double d = 0.0;
	for (int k = 0; k < HEAT_OUTPUTS; k++)
		for (int i = 0; i < HEAT_LENGTH; i++)
			d = worst_of(d, fabs(a->y[k][i] - b->y[k][i]));
	return d;
}

// Every vector CVODE, its nonlinear solvers and the linear solvers hand to the callbacks carries
// the operations. With SUNDIALS' sums put back, the run is SUNDIALS' own bit for bit: the same
// steps, the same values. With our sums, which differ from SUNDIALS' by rounding (1e-16
// relative), the runs differ where a decision (a step size, an iteration count) turns on the
// last bits: by the integration's own error at most. Both solutions are within 3e-8 of the
// closed form (tolerances 1e-8 relative, 1e-10 absolute; the solution is of magnitude 1), so
// they must agree to 5e-8.
static int test_cvode_with_and_without(void)
{
	heat_run ours, ours_but_sums, sundials;
	static const char* names[] = {"BDF, dense", "BDF, conjugate gradients", "Adams, fixed point"};
	for (int setup = HEAT_BDF_DENSE; setup <= HEAT_ADAMS_FIXED_POINT; setup++) {
		ENSURE(run_heat((heat_setup)setup, OPERATIONS_OURS, &ours) == 0);
		ENSURE(run_heat((heat_setup)setup, OPERATIONS_OURS_BUT_SUMS, &ours_but_sums) == 0);
		ENSURE(run_heat((heat_setup)setup, OPERATIONS_SUNDIALS, &sundials) == 0);
		const double difference = largest_difference(&ours, &sundials);
		printf("  %-25s steps %ld (SUNDIALS' %ld), |ours - SUNDIALS'| = %.2g, errors %.2g (SUNDIALS' "
		       "%.2g), %d vectors checked\n",
		       names[setup], ours.steps, sundials.steps, difference, ours.error, sundials.error,
		       ours.checked);
		ENSURE(ours.checked > 100 && ours.foreign == 0 && ours_but_sums.foreign == 0);
		ENSURE(ours_but_sums.steps == sundials.steps);
		ENSURE(largest_difference(&ours_but_sums, &sundials) == 0.0);
		ENSURE(ours.error < 3e-8 && sundials.error < 3e-8);
		ENSURE(difference <= 5e-8);
	}
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_linear_sum);
	RUN_TEST(test_scale_and_constant);
	RUN_TEST(test_products_quotients_abs_inverse);
	RUN_TEST(test_inverse_test_and_constraints);
	RUN_TEST(test_extremes);
	RUN_TEST(test_extremes_at_every_position);
	RUN_TEST(test_sums_and_norms);
	RUN_TEST(test_linear_combination);
	RUN_TEST(test_scale_add_multi_and_scale_array);
	RUN_TEST(test_dot_product_multi);
	RUN_TEST(test_fused_operations_across_blocks);
	RUN_TEST(test_installed_operations_and_clones);
	RUN_TEST(test_cvode_with_and_without);
	return TEST_SUMMARY();
}

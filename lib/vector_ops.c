// Vector operations for CVODE's serial state vectors, compiled with the project's flags.
//
// Debian's SUNDIALS libraries are built without optimisation: the serial N_Vector's loops load
// and store every variable on the stack. On the benchmark cloth those loops (linear sums in the
// prediction and the step's completion, the weighted RMS norms of the error and convergence
// tests) took 28 % of the run at n = 16 and 22 % at n = 32 (perf); the loops below take 5 %.
// sm_vector_ops_install puts them into a serial vector's table of operations; N_VClone copies
// the table, so every vector CVODE, its nonlinear solvers and the linear solvers clone from it
// uses them too.
//
// The semantics are SUNDIALS' documented ones (the N_Vector chapter of the SUNDIALS 6.4
// manual). Elementwise results are bit for bit those of SUNDIALS' serial vectors: each element
// is computed by the same operations in the same order. Sums are accumulated in four partial
// sums, so that their additions overlap instead of waiting for each other; they differ from a
// sequential sum by rounding only.
//
// SUNDIALS' vectors are either the same array or disjoint ones (z = x is allowed, a partial
// overlap never occurs), so every elementwise loop may write z[i] after reading x[i], y[i].
#include "simulation_internal.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

_Static_assert(_Generic((sunrealtype)0, double: 1, default: 0), "the loops below assume double precision");

// Elements per block of the fused operations: a block of the output and one of an input
// (2 x 8 KiB) stay in the L1 cache while several vectors are combined into the output.
enum { BLOCK_LENGTH = 1024 };

static inline sunindextype block_end(sunindextype start, sunindextype n)
{
	return n - start > BLOCK_LENGTH ? start + BLOCK_LENGTH : n;
}

// ---------------------------------------------------------------------------------------------
// Sums and extremes
// ---------------------------------------------------------------------------------------------

enum term_kind {
	TERM_PRODUCT,          // x_i w_i
	TERM_WEIGHTED_SQUARE,  // (x_i w_i)^2
	TERM_MASKED_SQUARE,    // (x_i w_i)^2 where id_i > 0, else 0
	TERM_ABSOLUTE,         // |x_i|
};

static inline double term(enum term_kind kind, const double* x, const double* w, const double* id,
                          sunindextype i)
{
	switch (kind) {
	case TERM_PRODUCT: return x[i] * w[i];
	case TERM_WEIGHTED_SQUARE: return (x[i] * w[i]) * (x[i] * w[i]);
	case TERM_MASKED_SQUARE: return id[i] > 0.0 ? (x[i] * w[i]) * (x[i] * w[i]) : 0.0;
	case TERM_ABSOLUTE: return fabs(x[i]);
	}
	return 0.0;
}

// Sum of the n terms of the given kind. One running sum waits for each addition in turn (about
// 4 cycles a term); four independent partial sums, added at the end, let the additions overlap.
// Adding 0 for a masked-out element leaves a sum unchanged, as skipping it would.
static inline double sum_terms(enum term_kind kind, const double* x, const double* w, const double* id,
                               sunindextype n)
{
	double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
	sunindextype i = 0;
	for (; i + 4 <= n; i += 4) {
		s0 += term(kind, x, w, id, i);
		s1 += term(kind, x, w, id, i + 1);
		s2 += term(kind, x, w, id, i + 2);
		s3 += term(kind, x, w, id, i + 3);
	}
	for (; i < n; i++)
		s0 += term(kind, x, w, id, i);
	return (s0 + s1) + (s2 + s3);
}

// The square root of a mean or sum of squares; 0 for s <= 0 and NaN for NaN (an empty vector's
// mean 0/0), as SUNDIALS' norms.
static double root(double s)
{
	return s <= 0.0 ? 0.0 : sqrt(s);
}

// ---------------------------------------------------------------------------------------------
// Standard operations
// ---------------------------------------------------------------------------------------------

// z = a x + b y. Weights +-1 (CVODE's prediction adds columns of its history array this way)
// take no multiplication: sums and differences of x and -x, y and -y (negation is exact, as
// multiplying by -1 is) run twice as fast in the L1 cache as the general loop (0.17 against
// 0.33 ns an element). Equal weights a = b (or a = -b) otherwise are applied after the sum,
// z = a (x +- y), as SUNDIALS' serial vectors do (CVODE calls it so: computed as a x + b y
// instead, its runs depart from SUNDIALS' in the last bits). One weight +-1 and the other
// general saves nothing over the general loop.
static void linear_sum(sunrealtype a, N_Vector xv, sunrealtype b, N_Vector yv, N_Vector zv)
{
	const double* x = NV_DATA_S(xv);
	const double* y = NV_DATA_S(yv);
	double* z = NV_DATA_S(zv);
	const sunindextype n = NV_LENGTH_S(zv);
	if (fabs(a) == 1.0 && fabs(b) == 1.0) {
		for (sunindextype i = 0; i < n; i++)
			z[i] = (a > 0.0 ? x[i] : -x[i]) + (b > 0.0 ? y[i] : -y[i]);
	} else if (a == b || a == -b) {
		const double sign = a == b ? 1.0 : -1.0;
		for (sunindextype i = 0; i < n; i++)
			z[i] = a * (x[i] + sign * y[i]);
	} else {
		for (sunindextype i = 0; i < n; i++)
			z[i] = a * x[i] + b * y[i];
	}
}

// The elementwise operations of one or two vectors and a scalar c, z_i = f(x_i, y_i):
enum map_kind {
	MAP_PRODUCT,       // x_i y_i
	MAP_QUOTIENT,      // x_i / y_i (y has no zero element: SUNDIALS does not test)
	MAP_SCALE,         // c x_i
	MAP_ABSOLUTE,      // |x_i|
	MAP_INVERSE,       // 1 / x_i (x has no zero element: SUNDIALS does not test)
	MAP_ADD_CONSTANT,  // x_i + c
	MAP_COMPARE,       // 1 if |x_i| >= c, else 0
};

static inline double map_element(enum map_kind kind, double c, const double* x, const double* y,
                                 sunindextype i)
{
	switch (kind) {
	case MAP_PRODUCT: return x[i] * y[i];
	case MAP_QUOTIENT: return x[i] / y[i];
	case MAP_SCALE: return c * x[i];
	case MAP_ABSOLUTE: return fabs(x[i]);
	case MAP_INVERSE: return 1.0 / x[i];
	case MAP_ADD_CONSTANT: return x[i] + c;
	case MAP_COMPARE: return fabs(x[i]) >= c ? 1.0 : 0.0;
	}
	return 0.0;
}

// One loop for all of them, specialised by the compiler for each constant kind. yv may be NULL
// for the kinds that do not read y.
static inline void map(enum map_kind kind, double c, N_Vector xv, N_Vector yv, N_Vector zv)
{
	const double* x = NV_DATA_S(xv);
	const double* y = yv ? NV_DATA_S(yv) : NULL;
	double* z = NV_DATA_S(zv);
	const sunindextype n = NV_LENGTH_S(zv);
	for (sunindextype i = 0; i < n; i++)
		z[i] = map_element(kind, c, x, y, i);
}

static void set_constant(sunrealtype c, N_Vector zv)
{
	double* z = NV_DATA_S(zv);
	const sunindextype n = NV_LENGTH_S(zv);
	for (sunindextype i = 0; i < n; i++)
		z[i] = c;
}

static void product(N_Vector xv, N_Vector yv, N_Vector zv)
{
	map(MAP_PRODUCT, 0.0, xv, yv, zv);
}

static void quotient(N_Vector xv, N_Vector yv, N_Vector zv)
{
	map(MAP_QUOTIENT, 0.0, xv, yv, zv);
}

// z = c x. A copy (c = 1, CVODE's way of copying a vector) is a memcpy; 1 x = x exactly.
static void scale(sunrealtype c, N_Vector xv, N_Vector zv)
{
	if (c == 1.0) {
		const sunindextype n = NV_LENGTH_S(zv);
		if (NV_DATA_S(zv) != NV_DATA_S(xv) && n > 0)
			memcpy(NV_DATA_S(zv), NV_DATA_S(xv), (size_t)n * sizeof(double));
		return;
	}
	map(MAP_SCALE, c, xv, NULL, zv);
}

static void absolute(N_Vector xv, N_Vector zv)
{
	map(MAP_ABSOLUTE, 0.0, xv, NULL, zv);
}

static void inverse(N_Vector xv, N_Vector zv)
{
	map(MAP_INVERSE, 0.0, xv, NULL, zv);
}

static void add_constant(N_Vector xv, sunrealtype b, N_Vector zv)
{
	map(MAP_ADD_CONSTANT, b, xv, NULL, zv);
}

static sunrealtype dot_product(N_Vector xv, N_Vector yv)
{
	return sum_terms(TERM_PRODUCT, NV_DATA_S(xv), NV_DATA_S(yv), NULL, NV_LENGTH_S(xv));
}

// max |x_i|, 0 for an empty vector; NaN elements are passed over (no comparison with NaN
// holds). Not on CVODE's path at every step: one running maximum.
static sunrealtype max_norm(N_Vector xv)
{
	const double* x = NV_DATA_S(xv);
	const sunindextype n = NV_LENGTH_S(xv);
	double m = 0.0;
	for (sunindextype i = 0; i < n; i++)
		if (fabs(x[i]) > m)
			m = fabs(x[i]);
	return m;
}

// The weighted sums of squares: sum (x_i w_i)^2, over the elements with id_i > 0 in the masked
// variant. CVODE's error and convergence tests call the weighted RMS norm several times a step.
static sunrealtype weighted_square_sum(N_Vector xv, N_Vector wv)
{
	return sum_terms(TERM_WEIGHTED_SQUARE, NV_DATA_S(xv), NV_DATA_S(wv), NULL, NV_LENGTH_S(xv));
}

static sunrealtype weighted_square_sum_masked(N_Vector xv, N_Vector wv, N_Vector idv)
{
	return sum_terms(TERM_MASKED_SQUARE, NV_DATA_S(xv), NV_DATA_S(wv), NV_DATA_S(idv), NV_LENGTH_S(xv));
}

// sqrt(sum (x_i w_i)^2 / n): NaN for an empty vector, as SUNDIALS'.
static sunrealtype weighted_rms_norm(N_Vector xv, N_Vector wv)
{
	return root(weighted_square_sum(xv, wv) / (double)NV_LENGTH_S(xv));
}

static sunrealtype weighted_rms_norm_masked(N_Vector xv, N_Vector wv, N_Vector idv)
{
	return root(weighted_square_sum_masked(xv, wv, idv) / (double)NV_LENGTH_S(xv));
}

// min x_i; SUN_BIG_REAL for an empty vector (SUNDIALS' serial vector reads its first element).
static sunrealtype minimum(N_Vector xv)
{
	const double* x = NV_DATA_S(xv);
	const sunindextype n = NV_LENGTH_S(xv);
	if (n == 0)
		return SUN_BIG_REAL;
	double m = x[0];
	for (sunindextype i = 1; i < n; i++)
		if (x[i] < m)
			m = x[i];
	return m;
}

static sunrealtype weighted_l2_norm(N_Vector xv, N_Vector wv)
{
	return root(weighted_square_sum(xv, wv));
}

static sunrealtype l1_norm(N_Vector xv)
{
	return sum_terms(TERM_ABSOLUTE, NV_DATA_S(xv), NULL, NULL, NV_LENGTH_S(xv));
}

static void compare(sunrealtype c, N_Vector xv, N_Vector zv)
{
	map(MAP_COMPARE, c, xv, NULL, zv);
}

// z_i = 1 / x_i where x_i != 0 (z_i is left as it is where x_i = 0); true if no x_i is 0.
static sunbooleantype inverse_test(N_Vector xv, N_Vector zv)
{
	const double* x = NV_DATA_S(xv);
	double* z = NV_DATA_S(zv);
	const sunindextype n = NV_LENGTH_S(zv);
	sunbooleantype all_nonzero = SUNTRUE;
	for (sunindextype i = 0; i < n; i++) {
		if (x[i] == 0.0)
			all_nonzero = SUNFALSE;
		else
			z[i] = 1.0 / x[i];
	}
	return all_nonzero;
}

// The constraint c_i on x_i: 2 means x_i > 0, 1 x_i >= 0, -1 x_i <= 0, -2 x_i < 0, 0 none.
// m_i = 1 where x_i violates its constraint, 0 where it holds; true if all hold. The codes are
// told apart by |c_i| > 1.5 (strict) and |c_i| > 0.5 (inclusive).
static sunbooleantype constraint_mask(N_Vector cv, N_Vector xv, N_Vector mv)
{
	const double* c = NV_DATA_S(cv);
	const double* x = NV_DATA_S(xv);
	double* m = NV_DATA_S(mv);
	const sunindextype n = NV_LENGTH_S(xv);
	sunbooleantype all_hold = SUNTRUE;
	for (sunindextype i = 0; i < n; i++) {
		bool violated = false;
		if (fabs(c[i]) > 1.5)
			violated = c[i] > 0.0 ? x[i] <= 0.0 : x[i] >= 0.0;
		else if (fabs(c[i]) > 0.5)
			violated = c[i] > 0.0 ? x[i] < 0.0 : x[i] > 0.0;
		m[i] = violated ? 1.0 : 0.0;
		if (violated)
			all_hold = SUNFALSE;
	}
	return all_hold;
}

// min num_i / denom_i over the elements with denom_i != 0; SUN_BIG_REAL if there is none.
static sunrealtype min_quotient(N_Vector numv, N_Vector denomv)
{
	const double* num = NV_DATA_S(numv);
	const double* denom = NV_DATA_S(denomv);
	const sunindextype n = NV_LENGTH_S(numv);
	bool found = false;
	double m = SUN_BIG_REAL;
	for (sunindextype i = 0; i < n; i++) {
		if (denom[i] == 0.0)
			continue;
		const double q = num[i] / denom[i];
		if (!found || q < m)
			m = q;
		found = true;
	}
	return m;
}

// ---------------------------------------------------------------------------------------------
// Fused operations (SUNDIALS' serial vectors leave them out by default: CVODE then calls one
// linear sum per vector instead). They return 0, or SM_NVEC_OUT_OF_RANGE for nvec < 1, as
// SUNDIALS' own do.
// ---------------------------------------------------------------------------------------------

// z = sum_j c_j X_j. z may be X[0] (only). Element by element the terms are added in the order
// of j, starting from c_0 X_0, which is the order of a sequence of linear sums; two vectors are
// a linear sum.
static int linear_combination(int nvec, sunrealtype* c, N_Vector* X, N_Vector zv)
{
	if (nvec < 1)
		return SM_NVEC_OUT_OF_RANGE;
	if (nvec == 1) {
		scale(c[0], X[0], zv);
		return 0;
	}
	if (nvec == 2) {
		linear_sum(c[0], X[0], c[1], X[1], zv);
		return 0;
	}
	double* z = NV_DATA_S(zv);
	const sunindextype n = NV_LENGTH_S(zv);
	for (sunindextype start = 0; start < n; start += BLOCK_LENGTH) {
		const sunindextype end = block_end(start, n);
		const double* x0 = NV_DATA_S(X[0]);
		for (sunindextype i = start; i < end; i++)
			z[i] = c[0] * x0[i];
		for (int j = 1; j < nvec; j++) {
			const double* x = NV_DATA_S(X[j]);
			const double cj = c[j];
			for (sunindextype i = start; i < end; i++)
				z[i] += cj * x[i];
		}
	}
	return 0;
}

// Z_j = c_j x + Y_j for every j (Z_j may be Y_j: CVODE's step completion adds l_j times the
// correction to each column of its history array).
static int scale_add_multi(int nvec, sunrealtype* c, N_Vector xv, N_Vector* Y, N_Vector* Z)
{
	if (nvec < 1)
		return SM_NVEC_OUT_OF_RANGE;
	const double* x = NV_DATA_S(xv);
	const sunindextype n = NV_LENGTH_S(xv);
	for (sunindextype start = 0; start < n; start += BLOCK_LENGTH) {
		const sunindextype end = block_end(start, n);
		for (int j = 0; j < nvec; j++) {
			const double* y = NV_DATA_S(Y[j]);
			double* z = NV_DATA_S(Z[j]);
			const double cj = c[j];
			for (sunindextype i = start; i < end; i++)
				z[i] = cj * x[i] + y[i];
		}
	}
	return 0;
}

// d_j = x . Y_j
static int dot_product_multi(int nvec, N_Vector xv, N_Vector* Y, sunrealtype* d)
{
	if (nvec < 1)
		return SM_NVEC_OUT_OF_RANGE;
	for (int j = 0; j < nvec; j++)
		d[j] = dot_product(xv, Y[j]);
	return 0;
}

// Z_j = c_j X_j (CVODE rescales its history array with it when the step size changes).
static int scale_vector_array(int nvec, sunrealtype* c, N_Vector* X, N_Vector* Z)
{
	if (nvec < 1)
		return SM_NVEC_OUT_OF_RANGE;
	for (int j = 0; j < nvec; j++)
		scale(c[j], X[j], Z[j]);
	return 0;
}

// ---------------------------------------------------------------------------------------------

void sm_vector_ops_install(N_Vector v)
{
	if (v == NULL || N_VGetVectorID(v) != SUNDIALS_NVEC_SERIAL)
		return;
	N_Vector_Ops ops = v->ops;
	ops->nvlinearsum = linear_sum;
	ops->nvconst = set_constant;
	ops->nvprod = product;
	ops->nvdiv = quotient;
	ops->nvscale = scale;
	ops->nvabs = absolute;
	ops->nvinv = inverse;
	ops->nvaddconst = add_constant;
	ops->nvdotprod = dot_product;
	ops->nvmaxnorm = max_norm;
	ops->nvwrmsnorm = weighted_rms_norm;
	ops->nvwrmsnormmask = weighted_rms_norm_masked;
	ops->nvmin = minimum;
	ops->nvwl2norm = weighted_l2_norm;
	ops->nvl1norm = l1_norm;
	ops->nvcompare = compare;
	ops->nvinvtest = inverse_test;
	ops->nvconstrmask = constraint_mask;
	ops->nvminquotient = min_quotient;

	// A serial vector is its own process's whole vector: the local reductions are the global ones.
	ops->nvdotprodlocal = dot_product;
	ops->nvmaxnormlocal = max_norm;
	ops->nvminlocal = minimum;
	ops->nvl1normlocal = l1_norm;
	ops->nvinvtestlocal = inverse_test;
	ops->nvconstrmasklocal = constraint_mask;
	ops->nvminquotientlocal = min_quotient;
	ops->nvwsqrsumlocal = weighted_square_sum;
	ops->nvwsqrsummasklocal = weighted_square_sum_masked;
	ops->nvdotprodmultilocal = dot_product_multi;

	ops->nvlinearcombination = linear_combination;
	ops->nvscaleaddmulti = scale_add_multi;
	ops->nvdotprodmulti = dot_product_multi;
	ops->nvscalevectorarray = scale_vector_array;
}

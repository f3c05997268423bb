// Evaluation of forces, energies and dissipated power (the laws are in law_*.h).
//
// The spring loop is the hot path of every simulation. It fuses the rest-length law
// (law_rest_length.h, which covers zero-length springs with l0 = 0) and spring damping
// (law_spring_damping.h) into one magnitude along u:
//
//   f_a = [ks (L - l0) + kd r] u,   f_b = -f_a,
//
// streams through the structure-of-arrays springs with no branch (disabled springs have zero
// constants; the degenerate point is a select, not a branch), four springs at a time where the
// processor has AVX, two at a time with SSE2 (every x86-64 processor), and accumulates into f.
// Every width gives the same bits. The same pass can also store every spring's Jacobian in
// factored form (sm_model_forces_and_jacobians), for the product in jacobian.c and the sparse
// fill in sparse_jacobian.c. bench/README.md has the measurements behind these choices.
#include "law_body_forces.h"
#include "law_rest_length.h"
#include "law_spring_damping.h"
#include "model_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// AVX is chosen at run time (the library is built for any x86-64), with GCC's or Clang's
// per-function target attribute.
#if defined(__SSE2__) && defined(__x86_64__) && defined(__GNUC__)
#define SM_HAVE_AVX_PATH 1
#include <immintrin.h>
#endif

// The loops below take constant flags and are expanded into each caller, so that the compiler
// makes one specialised loop per combination (without forcing it, it keeps one generic loop that
// tests the flags inside and runs short of registers).
#if defined(__GNUC__)
#define SPECIALISED static inline __attribute__((always_inline))
#else
#define SPECIALISED static inline
#endif

// Factored per-spring Jacobian (model.h, sm_spring_jacobians), evaluated in the same pass.
//
// Derivation. law_rest_length.h and law_spring_damping.h give, with g = 1 - l0/L,
// c = kd / L, r = u . dv and P = I - u u^T,
//
//   K = ks [u u^T + g P] + c [r P + u (P dv)^T]
//     = (ks g + c r) I + (ks (1 - g) - c r) u u^T + c u (dv - r u)^T
//     = beta I + u z^T
//
// with beta = ks g + c r and z = (ks - beta - c r) u + c dv, since ks (1 - g) - 2 c r
// = ks - beta - c r. The definiteness-preserving variant clamps g at zero and drops the
// damping-position term (c = 0): beta = ks g, z = (ks - beta) u, K = beta I + (ks - beta) u u^T,
// symmetric. At the degenerate point the geometry has u = 0 and 1/L = 0, so g = 1, c = 0 and
// K = ks I, as model.h states. D = kd u u^T needs only u and kd. Under a swap of the ends
// u, dv and z change sign and r does not, so u z^T and u u^T, hence K and D, are the same seen
// from either end (sparse_jacobian.c relies on it).
//
// The loop, specialised by the compiler for each combination of the constant flags:
// `with_velocity` (v given), `jacobian` (store the records), `clamp` (definite variant's clamp),
// `damping_position` (exact variant's c). The force is computed by the same expressions in
// every specialisation, so sm_model_forces and sm_model_forces_and_jacobians agree bit for bit.
SPECIALISED void spring_loop_scalar(int32_t begin, int32_t count, const int32_t* restrict first,
                                    const int32_t* restrict second, const double* restrict rest_length,
                                    const double* restrict stiffness, const double* restrict damping,
                                    const double* restrict x, const double* restrict v, double* restrict f,
                                    double* restrict jacobian, double* restrict power,
                                    const int with_velocity, const int with_jacobian, const int clamp,
                                    const int damping_position)
{
	double dissipated = 0.0;
	for (int32_t s = begin; s < count; s++) {
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		const double dx = x[b] - x[a], dy = x[b + 1] - x[a + 1], dz = x[b + 2] - x[a + 2];
		const double l0 = rest_length[s], ks = stiffness[s], kd = damping[s];
		const double length = sqrt(dx * dx + dy * dy + dz * dz);
		// Regular unless L = 0 or L < ratio * l0 (see model_internal.h, spring_geometry).
		const int regular = length > 0.0 && length >= SM_DEGENERATE_LENGTH_RATIO * l0;
		const double inv = 1.0 / (regular ? length : 1.0);
		const double inv_length = regular ? inv : 0.0;
		const double ux = dx * inv_length, uy = dy * inv_length, uz = dz * inv_length;
		double magnitude = rest_length_magnitude(ks, l0, length);
		double dvx = 0.0, dvy = 0.0, dvz = 0.0, rate = 0.0;
		if (with_velocity) {
			dvx = v[b] - v[a];
			dvy = v[b + 1] - v[a + 1];
			dvz = v[b + 2] - v[a + 2];
			rate = ux * dvx + uy * dvy + uz * dvz;
			magnitude += spring_damping_magnitude(kd, rate);
			if (power != NULL)
				dissipated += spring_damping_dissipation(kd, rate);
		}
		const double fx = magnitude * ux, fy = magnitude * uy, fz = magnitude * uz;
		f[a] += fx;
		f[a + 1] += fy;
		f[a + 2] += fz;
		f[b] -= fx;
		f[b + 1] -= fy;
		f[b + 2] -= fz;
		if (with_jacobian) {
			double g = 1.0 - l0 * inv_length;
			if (clamp)
				g = g < 0.0 ? 0.0 : g;
			const double c = damping_position ? kd * inv_length : 0.0;
			const double cr = c * rate;
			const double beta = ks * g + cr;
			const double axial = ks - beta - cr;
			double* restrict out = jacobian + SPRING_JACOBIAN_STRIDE * (size_t)s;
			out[0] = ux;
			out[1] = uy;
			out[2] = uz;
			out[3] = axial * ux + c * dvx;
			out[4] = axial * uy + c * dvy;
			out[5] = axial * uz + c * dvz;
			out[6] = beta;
			out[7] = kd;
		}
	}
	if (power != NULL)
		*power += dissipated;
}

#if defined(__SSE2__)
// The same loop, two springs at a time in the two lanes of SSE2 registers (part of every x86-64
// processor). Each lane performs exactly the scalar loop's IEEE operations in the same order
// (no fused multiply-add, no reassociation), so the results are the same bits; the square root
// and the division, the costliest operations, then serve two springs at once. The forces are
// added to f spring after spring, in the scalar loop's order, so that two springs of a pair
// sharing a particle accumulate as they would one at a time. Starts at spring `begin` (where the
// four-lane loop stopped) and returns where the scalar loop takes over (the odd last spring).
// The dissipated power is summed in two lanes, even and odd springs, carried in and out through
// `carried` (NULL: not wanted), so that the four-lane loop can hand its sums over unchanged.
SPECIALISED int32_t spring_loop_pairs(int32_t begin, int32_t count, const int32_t* restrict first,
                                      const int32_t* restrict second, const double* restrict rest_length,
                                      const double* restrict stiffness, const double* restrict damping,
                                      const double* restrict x, const double* restrict v, double* restrict f,
                                      double* restrict jacobian, double* restrict carried,
                                      const int with_velocity, const int with_jacobian, const int clamp,
                                      const int damping_position)
{
	const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0);
	__m128d dissipated = carried != NULL ? _mm_loadu_pd(carried) : zero;
	const __m128d ratio = _mm_set1_pd(SM_DEGENERATE_LENGTH_RATIO);
	int32_t s = begin;
	for (; s + 1 < count; s += 2) {
		const size_t a0 = 3 * (size_t)first[s], b0 = 3 * (size_t)second[s];
		const size_t a1 = 3 * (size_t)first[s + 1], b1 = 3 * (size_t)second[s + 1];
		// Component k of p at particle offsets i0 (low lane) and i1 (high lane).
#define PAIR(p, i0, i1, k) _mm_loadh_pd(_mm_load_sd((p) + (i0) + (k)), (p) + (i1) + (k))
		const __m128d dx = _mm_sub_pd(PAIR(x, b0, b1, 0), PAIR(x, a0, a1, 0));
		const __m128d dy = _mm_sub_pd(PAIR(x, b0, b1, 1), PAIR(x, a0, a1, 1));
		const __m128d dz = _mm_sub_pd(PAIR(x, b0, b1, 2), PAIR(x, a0, a1, 2));
		const __m128d l0 = _mm_loadu_pd(rest_length + s), ks = _mm_loadu_pd(stiffness + s);
		const __m128d kd = _mm_loadu_pd(damping + s);
		const __m128d length =
		    _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz)));
		const __m128d regular =
		    _mm_and_pd(_mm_cmpgt_pd(length, zero), _mm_cmpge_pd(length, _mm_mul_pd(ratio, l0)));
		const __m128d denominator = _mm_or_pd(_mm_and_pd(regular, length), _mm_andnot_pd(regular, one));
		const __m128d inv = _mm_div_pd(one, denominator);
		const __m128d inv_length = _mm_and_pd(regular, inv);
		const __m128d ux = _mm_mul_pd(dx, inv_length), uy = _mm_mul_pd(dy, inv_length);
		const __m128d uz = _mm_mul_pd(dz, inv_length);
		__m128d magnitude = _mm_mul_pd(ks, _mm_sub_pd(length, l0));
		__m128d dvx = zero, dvy = zero, dvz = zero, rate = zero;
		if (with_velocity) {
			dvx = _mm_sub_pd(PAIR(v, b0, b1, 0), PAIR(v, a0, a1, 0));
			dvy = _mm_sub_pd(PAIR(v, b0, b1, 1), PAIR(v, a0, a1, 1));
			dvz = _mm_sub_pd(PAIR(v, b0, b1, 2), PAIR(v, a0, a1, 2));
			rate = _mm_add_pd(_mm_add_pd(_mm_mul_pd(ux, dvx), _mm_mul_pd(uy, dvy)), _mm_mul_pd(uz, dvz));
			magnitude = _mm_add_pd(magnitude, _mm_mul_pd(kd, rate));
			if (carried != NULL)  // kd r^2 (law_spring_damping.h), lane by lane
				dissipated = _mm_add_pd(dissipated, _mm_mul_pd(_mm_mul_pd(kd, rate), rate));
		}
#undef PAIR
		const __m128d fx = _mm_mul_pd(magnitude, ux), fy = _mm_mul_pd(magnitude, uy);
		const __m128d fz = _mm_mul_pd(magnitude, uz);
		const __m128d fxy0 = _mm_unpacklo_pd(fx, fy), fxy1 = _mm_unpackhi_pd(fx, fy);
		const __m128d fz1 = _mm_unpackhi_pd(fz, fz);
		_mm_storeu_pd(f + a0, _mm_add_pd(_mm_loadu_pd(f + a0), fxy0));
		_mm_store_sd(f + a0 + 2, _mm_add_sd(_mm_load_sd(f + a0 + 2), fz));
		_mm_storeu_pd(f + b0, _mm_sub_pd(_mm_loadu_pd(f + b0), fxy0));
		_mm_store_sd(f + b0 + 2, _mm_sub_sd(_mm_load_sd(f + b0 + 2), fz));
		_mm_storeu_pd(f + a1, _mm_add_pd(_mm_loadu_pd(f + a1), fxy1));
		_mm_store_sd(f + a1 + 2, _mm_add_sd(_mm_load_sd(f + a1 + 2), fz1));
		_mm_storeu_pd(f + b1, _mm_sub_pd(_mm_loadu_pd(f + b1), fxy1));
		_mm_store_sd(f + b1 + 2, _mm_sub_sd(_mm_load_sd(f + b1 + 2), fz1));
		if (with_jacobian) {
			__m128d g = _mm_sub_pd(one, _mm_mul_pd(l0, inv_length));
			if (clamp)
				g = _mm_andnot_pd(_mm_cmplt_pd(g, zero), g);  // g < 0 ? 0 : g
			const __m128d c = damping_position ? _mm_mul_pd(kd, inv_length) : zero;
			const __m128d cr = _mm_mul_pd(c, rate);
			const __m128d beta = _mm_add_pd(_mm_mul_pd(ks, g), cr);
			const __m128d axial = _mm_sub_pd(_mm_sub_pd(ks, beta), cr);
			const __m128d zx = _mm_add_pd(_mm_mul_pd(axial, ux), _mm_mul_pd(c, dvx));
			const __m128d zy = _mm_add_pd(_mm_mul_pd(axial, uy), _mm_mul_pd(c, dvy));
			const __m128d zz = _mm_add_pd(_mm_mul_pd(axial, uz), _mm_mul_pd(c, dvz));
			double* out = jacobian + SPRING_JACOBIAN_STRIDE * (size_t)s;  // 64-byte aligned records
			_mm_store_pd(out, _mm_unpacklo_pd(ux, uy));
			_mm_store_pd(out + 2, _mm_unpacklo_pd(uz, zx));
			_mm_store_pd(out + 4, _mm_unpacklo_pd(zy, zz));
			_mm_store_pd(out + 6, _mm_unpacklo_pd(beta, kd));
			_mm_store_pd(out + 8, _mm_unpackhi_pd(ux, uy));
			_mm_store_pd(out + 10, _mm_unpackhi_pd(uz, zx));
			_mm_store_pd(out + 12, _mm_unpackhi_pd(zy, zz));
			_mm_store_pd(out + 14, _mm_unpackhi_pd(beta, kd));
		}
	}
	if (carried != NULL)
		_mm_storeu_pd(carried, dissipated);
	return s;
}
#endif

#if defined(SM_HAVE_AVX_PATH)
#define AVX_TARGET __attribute__((target("avx")))

// The loops over a register's four lanes are unrolled whatever the optimisation level. Left as
// loops (GCC's -O2, RelWithDebInfo's level, keeps them), their arrays go through the stack and
// the 256-bit loads of lanes stored one at a time stall store forwarding: at -O2 the four-lane
// loop took 2.2 times the pairs' time (Zen 4; bench/README.md).
#define FOR_EACH_LANE _Pragma("GCC unroll 4") for (int k = 0; k < 4; k++)

// Lanes of 256-bit registers: (a, b) of four springs' 128-bit pairs, and back.
#define AVX_JOIN(lo, hi) _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), (hi), 1)

// The same loop, four springs at a time in the four lanes of AVX registers, for processors that
// have AVX (chosen at run time: avx_available). Each lane performs exactly the scalar loop's IEEE
// operations in the same order (the target enables neither FMA nor reassociation), so the results
// are the same bits as the pairs' and the scalar loop's; a 256-bit square root or division costs
// about what a 128-bit one does on current processors (Zen 4: 0.95 against 1.95 ns per element,
// measured for the pair sqrt-then-divide), so four springs share what two did. The forces are
// added to f spring after spring; the dissipated power's lanes 0 and 2 (even springs) and 1 and 3
// (odd) are added into the pairs' two sums in the order the pairs loop adds them. Returns where
// the pairs loop takes over.
static inline AVX_TARGET __attribute__((always_inline)) int32_t spring_loop_quads(
    int32_t count, const int32_t* restrict first, const int32_t* restrict second,
    const double* restrict rest_length, const double* restrict stiffness, const double* restrict damping,
    const double* restrict x, const double* restrict v, double* restrict f, double* restrict jacobian,
    double* restrict carried, const int with_velocity, const int with_jacobian, const int clamp,
    const int damping_position)
{
	const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
	const __m256d ratio = _mm256_set1_pd(SM_DEGENERATE_LENGTH_RATIO);
	__m128d dissipated = carried != NULL ? _mm_loadu_pd(carried) : _mm_setzero_pd();
	int32_t s = 0;
	for (; s + 3 < count; s += 4) {
		size_t a[4], b[4];
		FOR_EACH_LANE
		{
			a[k] = 3 * (size_t)first[s + k];
			b[k] = 3 * (size_t)second[s + k];
		}
		// (x, y) differences spring by spring in 128-bit registers, z differences as scalars,
		// then transposed into one register per component (lane k: spring s + k).
#define DIFFERENCES(p, ox, oy, oz)                                                                           \
	do {                                                                                                     \
		__m128d xy[4];                                                                                       \
		double dzs[4];                                                                                       \
		FOR_EACH_LANE                                                                                        \
		{                                                                                                    \
			xy[k] = _mm_sub_pd(_mm_loadu_pd((p) + b[k]), _mm_loadu_pd((p) + a[k]));                          \
			dzs[k] = (p)[b[k] + 2] - (p)[a[k] + 2];                                                          \
		}                                                                                                    \
		const __m256d even = AVX_JOIN(xy[0], xy[2]), odd = AVX_JOIN(xy[1], xy[3]);                           \
		ox = _mm256_unpacklo_pd(even, odd);                                                                  \
		oy = _mm256_unpackhi_pd(even, odd);                                                                  \
		oz = _mm256_loadu_pd(dzs);                                                                           \
	} while (0)
		__m256d dx, dy, dz;
		DIFFERENCES(x, dx, dy, dz);
		const __m256d l0 = _mm256_loadu_pd(rest_length + s), ks = _mm256_loadu_pd(stiffness + s);
		const __m256d kd = _mm256_loadu_pd(damping + s);
		const __m256d length = _mm256_sqrt_pd(_mm256_add_pd(
		    _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)));
		const __m256d regular = _mm256_and_pd(_mm256_cmp_pd(length, zero, _CMP_GT_OQ),
		                                      _mm256_cmp_pd(length, _mm256_mul_pd(ratio, l0), _CMP_GE_OQ));
		const __m256d inv = _mm256_div_pd(one, _mm256_blendv_pd(one, length, regular));
		const __m256d inv_length = _mm256_and_pd(regular, inv);
		const __m256d ux = _mm256_mul_pd(dx, inv_length), uy = _mm256_mul_pd(dy, inv_length);
		const __m256d uz = _mm256_mul_pd(dz, inv_length);
		__m256d magnitude = _mm256_mul_pd(ks, _mm256_sub_pd(length, l0));
		__m256d dvx = zero, dvy = zero, dvz = zero, rate = zero;
		if (with_velocity) {
			DIFFERENCES(v, dvx, dvy, dvz);
			rate = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ux, dvx), _mm256_mul_pd(uy, dvy)),
			                     _mm256_mul_pd(uz, dvz));
			magnitude = _mm256_add_pd(magnitude, _mm256_mul_pd(kd, rate));
			if (carried != NULL) {  // kd r^2 (law_spring_damping.h): springs s, s + 1, then s + 2, s + 3
				const __m256d terms = _mm256_mul_pd(_mm256_mul_pd(kd, rate), rate);
				dissipated = _mm_add_pd(dissipated, _mm256_castpd256_pd128(terms));
				dissipated = _mm_add_pd(dissipated, _mm256_extractf128_pd(terms, 1));
			}
		}
#undef DIFFERENCES
		const __m256d fx = _mm256_mul_pd(magnitude, ux), fy = _mm256_mul_pd(magnitude, uy);
		const __m256d fz = _mm256_mul_pd(magnitude, uz);
		// (fx, fy) of springs s, s + 2 and of s + 1, s + 3, then one 128-bit pair per spring.
		const __m256d xy_even = _mm256_unpacklo_pd(fx, fy), xy_odd = _mm256_unpackhi_pd(fx, fy);
		const __m128d fxy[4] = {_mm256_castpd256_pd128(xy_even), _mm256_castpd256_pd128(xy_odd),
		                        _mm256_extractf128_pd(xy_even, 1), _mm256_extractf128_pd(xy_odd, 1)};
		double fzs[4];
		_mm256_storeu_pd(fzs, fz);
		FOR_EACH_LANE
		{
			_mm_storeu_pd(f + a[k], _mm_add_pd(_mm_loadu_pd(f + a[k]), fxy[k]));
			f[a[k] + 2] += fzs[k];
			_mm_storeu_pd(f + b[k], _mm_sub_pd(_mm_loadu_pd(f + b[k]), fxy[k]));
			f[b[k] + 2] -= fzs[k];
		}
		if (with_jacobian) {
			__m256d g = _mm256_sub_pd(one, _mm256_mul_pd(l0, inv_length));
			if (clamp)
				g = _mm256_andnot_pd(_mm256_cmp_pd(g, zero, _CMP_LT_OQ), g);  // g < 0 ? 0 : g
			const __m256d c = damping_position ? _mm256_mul_pd(kd, inv_length) : zero;
			const __m256d cr = _mm256_mul_pd(c, rate);
			const __m256d beta = _mm256_add_pd(_mm256_mul_pd(ks, g), cr);
			const __m256d axial = _mm256_sub_pd(_mm256_sub_pd(ks, beta), cr);
			const __m256d zx = _mm256_add_pd(_mm256_mul_pd(axial, ux), _mm256_mul_pd(c, dvx));
			const __m256d zy = _mm256_add_pd(_mm256_mul_pd(axial, uy), _mm256_mul_pd(c, dvy));
			const __m256d zz = _mm256_add_pd(_mm256_mul_pd(axial, uz), _mm256_mul_pd(c, dvz));
			// Transposes (ux, uy, uz, zx) and (zy, zz, beta, kd) of four springs into their records.
			const __m256d t0 = _mm256_unpacklo_pd(ux, uy), t1 = _mm256_unpackhi_pd(ux, uy);
			const __m256d t2 = _mm256_unpacklo_pd(uz, zx), t3 = _mm256_unpackhi_pd(uz, zx);
			const __m256d t4 = _mm256_unpacklo_pd(zy, zz), t5 = _mm256_unpackhi_pd(zy, zz);
			const __m256d t6 = _mm256_unpacklo_pd(beta, kd), t7 = _mm256_unpackhi_pd(beta, kd);
			double* out = jacobian + SPRING_JACOBIAN_STRIDE * (size_t)s;  // 64-byte aligned records
			_mm256_store_pd(out, _mm256_permute2f128_pd(t0, t2, 0x20));
			_mm256_store_pd(out + 4, _mm256_permute2f128_pd(t4, t6, 0x20));
			_mm256_store_pd(out + 8, _mm256_permute2f128_pd(t1, t3, 0x20));
			_mm256_store_pd(out + 12, _mm256_permute2f128_pd(t5, t7, 0x20));
			_mm256_store_pd(out + 16, _mm256_permute2f128_pd(t0, t2, 0x31));
			_mm256_store_pd(out + 20, _mm256_permute2f128_pd(t4, t6, 0x31));
			_mm256_store_pd(out + 24, _mm256_permute2f128_pd(t1, t3, 0x31));
			_mm256_store_pd(out + 28, _mm256_permute2f128_pd(t5, t7, 0x31));
		}
	}
	if (carried != NULL)
		_mm_storeu_pd(carried, dissipated);
	return s;
}

// The four-lane loop for each combination of the flags that springs_add uses (the loop must be
// expanded inside a function compiled for AVX). Returns where the pairs loop takes over: 0 for
// any other combination.
static AVX_TARGET int32_t spring_quads(int32_t count, const int32_t* first, const int32_t* second,
                                       const double* rest_length, const double* stiffness,
                                       const double* damping, const double* x, const double* v, double* f,
                                       double* jacobian, double* carried, const int with_velocity,
                                       const int with_jacobian, const int clamp, const int damping_position)
{
#define QUADS(c, wv, wj, cl, dp)                                                                             \
	spring_loop_quads(count, first, second, rest_length, stiffness, damping, x, v, f, jacobian, c, wv, wj,   \
	                  cl, dp)
	const int flags = with_velocity << 3 | with_jacobian << 2 | clamp << 1 | damping_position;
	const bool sums = carried != NULL;
	switch (flags) {
	// Without velocities no loop sums a power: the sums are left as they are.
	case 0x0: return QUADS(NULL, 0, 0, 0, 0);
	case 0x8: return sums ? QUADS(carried, 1, 0, 0, 0) : QUADS(NULL, 1, 0, 0, 0);
	case 0x4: return QUADS(NULL, 0, 1, 0, 0);
	case 0x6: return QUADS(NULL, 0, 1, 1, 0);
	case 0xd: return sums ? QUADS(carried, 1, 1, 0, 1) : QUADS(NULL, 1, 1, 0, 1);
	case 0xe: return sums ? QUADS(carried, 1, 1, 1, 0) : QUADS(NULL, 1, 1, 1, 0);
	default: return 0;
	}
#undef QUADS
}

// Whether this processor and its operating system run AVX instructions (libgcc's or
// compiler-rt's record of the processor, filled in before main).
static bool avx_available(void)
{
	return __builtin_cpu_supports("avx");
}
#endif

// Springs at a time that this processor allows: 4 with AVX, 2 with SSE2, else 1.
static int widest_lanes(void)
{
#if defined(SM_HAVE_AVX_PATH)
	return avx_available() ? 4 : 2;
#elif defined(__SSE2__)
	return 2;
#else
	return 1;
#endif
}

// The whole loop, at most `lanes` springs at a time: four-lane, then pairs, then the scalar loop
// for what is left (the same bits whichever way, see above; the power's two lanes are added last,
// as the pairs loop always did).
SPECIALISED void spring_loop(int lanes, int32_t count, const int32_t* restrict first,
                             const int32_t* restrict second, const double* restrict rest_length,
                             const double* restrict stiffness, const double* restrict damping,
                             const double* restrict x, const double* restrict v, double* restrict f,
                             double* restrict jacobian, double* restrict power, const int with_velocity,
                             const int with_jacobian, const int clamp, const int damping_position)
{
	int32_t begin = 0;
#if defined(__SSE2__)
	double sums[2] = {0.0, 0.0};
	double* carried = power != NULL ? sums : NULL;
#if defined(SM_HAVE_AVX_PATH)
	if (lanes >= 4)
		begin = spring_quads(count, first, second, rest_length, stiffness, damping, x, v, f, jacobian,
		                     carried, with_velocity, with_jacobian, clamp, damping_position);
#endif
	if (lanes >= 2)
		begin = spring_loop_pairs(begin, count, first, second, rest_length, stiffness, damping, x, v, f,
		                          jacobian, carried, with_velocity, with_jacobian, clamp, damping_position);
	if (power != NULL)
		*power += sums[0] + sums[1];
#else
	(void)lanes;
#endif
	spring_loop_scalar(begin, count, first, second, rest_length, stiffness, damping, x, v, f, jacobian, power,
	                   with_velocity, with_jacobian, clamp, damping_position);
}

// Adds the springs' forces to f, with v their damping (v NULL: none), with `jacobian` every
// spring's record of `variant` (NULL: none), and with `power` their dissipated power (v given),
// each combination in a loop of its own.
static void springs_add(const sm_model* m, const double* x, const double* v, double* f, double* jacobian,
                        sm_jacobian_variant variant, double* power, int lanes)
{
#define LOOP(vv, jj, pp, wv, wj, cl, dp)                                                                     \
	spring_loop(lanes, m->spring_count, m->spring_a, m->spring_b, m->rest_length, m->stiffness, m->damping,  \
	            x, vv, f, jj, pp, wv, wj, cl, dp)
	const bool exact = variant == SM_JACOBIAN_EXACT;
	// Exact: no clamp, the damping-position term (none without v). Definite: clamp, no term.
	if (jacobian == NULL && v == NULL)
		LOOP(NULL, NULL, NULL, 0, 0, 0, 0);
	else if (jacobian == NULL && power == NULL)
		LOOP(v, NULL, NULL, 1, 0, 0, 0);
	else if (jacobian == NULL)
		LOOP(v, NULL, power, 1, 0, 0, 0);
	else if (v == NULL && exact)
		LOOP(NULL, jacobian, NULL, 0, 1, 0, 0);
	else if (v == NULL)
		LOOP(NULL, jacobian, NULL, 0, 1, 1, 0);
	else if (exact && power == NULL)
		LOOP(v, jacobian, NULL, 1, 1, 0, 1);
	else if (exact)
		LOOP(v, jacobian, power, 1, 1, 0, 1);
	else if (power == NULL)
		LOOP(v, jacobian, NULL, 1, 1, 1, 0);
	else
		LOOP(v, jacobian, power, 1, 1, 1, 0);
#undef LOOP
}

void sm_model_spring_forces_lanes(const sm_model* model, const double* x, const double* v, double* f,
                                  sm_spring_jacobians* jacobians, sm_jacobian_variant variant, double* power,
                                  int lanes)
{
	// A processor without AVX (or SSE2) would fault on the wider loops: at most its widest.
	const int widest = widest_lanes();
	springs_add(model, x, v, f, jacobians != NULL ? jacobians->data : NULL, variant, v != NULL ? power : NULL,
	            lanes < widest ? lanes : widest);
}

// Gravity, mass damping, loads and external forces on particles begin .. end - 1: the starting
// value of their f before the springs add. Each particle's external force is read before its f
// is written, so that f_external may be f itself (model.h); the sums are the same either way:
// m (g - alpha v), then the load, then the external force.
static void body_forces_range(const sm_model* model, const double* v, const double* f_external, double* f,
                              int32_t begin, int32_t end)
{
	static const double zero[3] = {0.0, 0.0, 0.0};
	const double* load = model->load_count > 0 ? model->load : NULL;
	for (int32_t i = begin; i < end; i++) {
		const size_t at = 3 * (size_t)i;
		const double* vi = v != NULL ? v + at : zero;
		double fi[3];
		body_force(model->mass[i], model->def.gravity, model->def.mass_damping, vi, fi);
		for (int k = 0; k < 3; k++) {
			if (load != NULL)
				fi[k] += load[at + k];
			if (f_external != NULL)
				fi[k] += f_external[at + k];
			f[at + k] = fi[k];
		}
	}
}

static void body_forces(const sm_model* model, const double* v, const double* f_external, double* f)
{
	body_forces_range(model, v, f_external, f, 0, model->particle_count);
}

void sm_model_forces(const sm_model* model, const double* x, const double* v, const double* f_external,
                     double* f)
{
	if (model == NULL || x == NULL || f == NULL)
		return;
	body_forces(model, v, f_external, f);
	springs_add(model, x, v, f, NULL, SM_JACOBIAN_EXACT, NULL, widest_lanes());
}

// Power dissipated by mass damping over particles begin .. end - 1 [W].
static double mass_damping_power_range(const sm_model* model, const double* v, int32_t begin, int32_t end)
{
	double power = 0.0;
	for (int32_t i = begin; i < end; i++)
		power += mass_damping_dissipation(model->mass[i], model->def.mass_damping, v + 3 * (size_t)i);
	return power;
}

static double mass_damping_power(const sm_model* model, const double* v)
{
	return mass_damping_power_range(model, v, 0, model->particle_count);
}

double sm_model_forces_and_power(const sm_model* model, const double* x, const double* v,
                                 const double* f_external, double* f)
{
	body_forces(model, v, f_external, f);
	double power = 0.0;
	springs_add(model, x, v, f, NULL, SM_JACOBIAN_EXACT, &power, widest_lanes());
	return power + mass_damping_power(model, v);
}

double sm_model_forces_power_and_jacobians(const sm_model* model, const double* x, const double* v,
                                           const double* f_external, double* f,
                                           sm_spring_jacobians* jacobians)
{
	body_forces(model, v, f_external, f);
	double power = 0.0;
	springs_add(model, x, v, f, jacobians->data, SM_JACOBIAN_DEFINITE, &power, widest_lanes());
	jacobians->variant = SM_JACOBIAN_DEFINITE;
	jacobians->evaluated = 1;
	return power + mass_damping_power(model, v);
}

double sm_model_body_forces_range(const sm_model* model, const double* v, const double* f_external, double* f,
                                  int32_t begin, int32_t end)
{
	body_forces_range(model, v, f_external, f, begin, end);
	return mass_damping_power_range(model, v, begin, end);
}

double sm_spring_order_forces_and_jacobians(const sm_spring_order* order, int32_t begin, int32_t end,
                                            const double* x, const double* v, double* f, double* records)
{
	double power = 0.0;
	if (begin < end)
		spring_loop(widest_lanes(), end - begin, order->a + begin, order->b + begin,
		            order->rest_length + begin, order->stiffness + begin, order->damping + begin, x, v, f,
		            records + SPRING_JACOBIAN_STRIDE * (size_t)begin, &power, 1, 1, 1, 0);
	return power;
}

sm_spring_jacobians* sm_spring_jacobians_create(const sm_model* model)
{
	if (model == NULL)
		return NULL;
	sm_spring_jacobians* j = calloc(1, sizeof *j);
	if (j == NULL)
		return NULL;
	j->particle_count = model->particle_count;
	j->spring_count = model->spring_count;
	// One 64-byte record per spring; aligned_alloc wants a size that is a multiple of 64.
	const size_t records = (size_t)model->spring_count + 1;
	j->data = aligned_alloc(64, records * SPRING_JACOBIAN_STRIDE * sizeof(double));
	if (j->data == NULL) {
		free(j);
		return NULL;
	}
	return j;
}

void sm_spring_jacobians_destroy(sm_spring_jacobians* jacobians)
{
	if (jacobians == NULL)
		return;
	free(jacobians->data);
	free(jacobians);
}

sm_status sm_model_forces_and_jacobians(const sm_model* model, const double* x, const double* v,
                                        const double* f_external, sm_jacobian_variant variant, double* f,
                                        sm_spring_jacobians* jacobians)
{
	if (model == NULL || x == NULL || f == NULL || jacobians == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (variant != SM_JACOBIAN_EXACT && variant != SM_JACOBIAN_DEFINITE)
		return SM_ERROR_INVALID_ARGUMENT;
	if (jacobians->particle_count != model->particle_count || jacobians->spring_count != model->spring_count)
		return SM_ERROR_TOPOLOGY;
	body_forces(model, v, f_external, f);
	springs_add(model, x, v, f, jacobians->data, variant, NULL, widest_lanes());
	jacobians->variant = variant;
	jacobians->evaluated = 1;
	return SM_OK;
}

sm_energies sm_model_energies(const sm_model* model, const double* x, const double* v)
{
	sm_energies e = {0.0, 0.0, 0.0};
	if (model == NULL)
		return e;
	const double* g = model->def.gravity;
	for (int32_t i = 0; i < model->particle_count; i++) {
		const double m = model->mass[i];
		if (v != NULL) {
			const double* vi = v + 3 * (size_t)i;
			e.kinetic += 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
		}
		if (x != NULL)
			e.gravity += constant_force_potential(m, g, model->load + 3 * (size_t)i, x + 3 * (size_t)i);
	}
	if (x != NULL)
		for (int32_t s = 0; s < model->spring_count; s++) {
			spring_geometry geo;
			spring_geometry_eval(x, NULL, model->spring_a[s], model->spring_b[s], model->rest_length[s],
			                     &geo);
			// Zero-length springs have l0 = 0: ks (L - 0)^2 / 2 = ks L^2 / 2 (law_zero_length.h).
			e.elastic += rest_length_energy(model->stiffness[s], model->rest_length[s], geo.length);
		}
	return e;
}

double sm_model_particle_energy(const sm_model* model, const double* x, const double* v, int32_t i,
                                const int32_t* springs, int32_t count)
{
	const double m = model->mass[i];
	const double* g = model->def.gravity;
	const double* xi = x + 3 * (size_t)i;
	const double* vi = v + 3 * (size_t)i;
	double energy = 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]) +
	                constant_force_potential(m, g, model->load + 3 * (size_t)i, xi);
	for (int32_t k = 0; k < count; k++) {
		const int32_t s = springs[k];
		spring_geometry geo;
		spring_geometry_eval(x, NULL, model->spring_a[s], model->spring_b[s], model->rest_length[s], &geo);
		energy += rest_length_energy(model->stiffness[s], model->rest_length[s], geo.length);
	}
	return energy;
}

double sm_model_spring_energy(const sm_model* model, int32_t s, const double xa[3], const double xb[3])
{
	const double x[6] = {xa[0], xa[1], xa[2], xb[0], xb[1], xb[2]};
	spring_geometry geo;
	spring_geometry_eval(x, NULL, 0, 1, model->rest_length[s], &geo);
	return rest_length_energy(model->stiffness[s], model->rest_length[s], geo.length);
}

double sm_model_spring_force(const sm_model* model, int32_t s, const double xa[3], const double xb[3],
                             const double va[3], const double vb[3], double f_a[3])
{
	const double x[6] = {xa[0], xa[1], xa[2], xb[0], xb[1], xb[2]};
	const double v[6] = {va[0], va[1], va[2], vb[0], vb[1], vb[2]};
	spring_geometry geo;
	spring_geometry_eval(x, v, 0, 1, model->rest_length[s], &geo);
	const double magnitude = rest_length_magnitude(model->stiffness[s], model->rest_length[s], geo.length) +
	                         spring_damping_magnitude(model->damping[s], geo.rate);
	for (int c = 0; c < 3; c++)
		f_a[c] = magnitude * geo.u[c];
	return spring_damping_dissipation(model->damping[s], geo.rate);
}

double sm_model_dissipated_power(const sm_model* model, const double* x, const double* v)
{
	if (model == NULL || v == NULL)
		return 0.0;
	double power = mass_damping_power(model, v);
	if (x == NULL)
		return power;
	for (int32_t s = 0; s < model->spring_count; s++) {
		spring_geometry geo;
		spring_geometry_eval(x, v, model->spring_a[s], model->spring_b[s], model->rest_length[s], &geo);
		power += spring_damping_dissipation(model->damping[s], geo.rate);
	}
	return power;
}

// The force on a is f_a = (ks (L - l0) + kd r) u (law_rest_length.h, law_spring_damping.h): its
// magnitude along u, positive when the spring pulls, is the tension. At the singular point
// (L = 0, or L < SM_DEGENERATE_LENGTH_RATIO l0) the geometry has no direction (u = 0) and the
// spring exerts no force: tension 0. A length that is not finite is no singular point, although
// its 1/L is 0 as well: a NaN length gives a NaN tension and an overflowed one (L = inf, u = 0,
// r = 0) ks (inf - l0) = inf, so that a state gone wrong does not read as a slack spring. A
// disabled spring (ks = kd = 0) pulls with 0 at any length (0 inf would be NaN).
void sm_model_spring_states(const sm_model* model, const double* x, const double* v, double* length,
                            double* strain, double* tension)
{
	if (model == NULL || x == NULL)
		return;
	for (int32_t s = 0; s < model->spring_count; s++) {
		spring_geometry geo;
		spring_geometry_eval(x, v, model->spring_a[s], model->spring_b[s], model->rest_length[s], &geo);
		const double l0 = model->rest_length[s];
		if (length != NULL)
			length[s] = geo.length;
		if (strain != NULL)
			strain[s] = l0 > 0.0 ? (geo.length - l0) / l0 : NAN;
		if (tension != NULL) {
			const bool singular = geo.length == 0.0 || geo.length < SM_DEGENERATE_LENGTH_RATIO * l0;
			tension[s] = model->enabled[s] && !singular
			                 ? rest_length_magnitude(model->stiffness[s], l0, geo.length) +
			                       spring_damping_magnitude(model->damping[s], geo.rate)
			                 : 0.0;
		}
	}
}

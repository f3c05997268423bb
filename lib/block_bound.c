// A bound on the eigenvalues of a symmetric matrix made of 3x3 blocks, one per pair of free
// particles (the stiffness K over the free degrees of freedom, or M^(-1/2) K M^(-1/2)), that does
// not change when the model is turned (analysis_internal.h, sm_block_row_bound).
//
// Gershgorin's row sums of |A_ij| change with the axes: a spring's block k u u^T has the row sum
// k |u_i| (|u_x| + |u_y| + |u_z|), k for a spring along an axis but (1 + sqrt 2)/2 k = 1.21 k
// for one at 22.5 degrees to it. Whole blocks do not. Let A be symmetric with blocks A_pq
// (A_qp = A_pq^T), x = (x_p) any vector, and split an off-diagonal block A_pq = S + W into its
// symmetric part S = sum_i s_i e_i e_i^T (e_i orthonormal) and its antisymmetric part
// W x = w x x (||W||_2 = |w|). With |S| = sum_i |s_i| e_i e_i^T,
//
//   2 x_p^T S x_q = sum_i 2 s_i (e_i . x_p)(e_i . x_q) <= x_p^T |S| x_p + x_q^T |S| x_q,
//   2 x_p^T W x_q <= 2 |w| |x_p| |x_q|                  <= |w| (|x_p|^2 + |x_q|^2),
//
// (2 a b <= a^2 + b^2), and the block A_qp = S - W gives the same |S| and |w|. Summing
// x^T A x = sum_p x_p^T A_pp x_p + sum_{p<q} 2 x_p^T A_pq x_q over the pairs,
//
//   sum_p x_p^T L_p x_p <= x^T A x <= sum_p x_p^T T_p x_p,
//   T_p, L_p = sym(A_pp) +- sum_{q != p} (|S_pq| + |w_pq| I),
//
// so by the Rayleigh quotient every eigenvalue of A lies in [min_p lambda_min(L_p),
// max_p lambda_max(T_p)], and |lambda| <= max_p max(lambda_max(T_p), -lambda_min(L_p)): the
// bound of block row p. It needs no row but p's, so its cost is linear in the blocks. Turning the
// model by a rotation R turns every block into R A_pq R^T, hence S, W, T_p and L_p likewise, and
// their eigenvalues stay. With symmetric blocks (a spring's) it is at most the sum of the
// blocks' spectral norms over a block row (the largest eigenvalue of a sum of symmetric matrices
// is at most the sum of theirs), and it is attained where one vector turns every inequality into
// an equality: u . x_q = -u . x_p along each spring's direction u, x_p the top eigenvector of
// T_p, as in the highest mode of a uniform chain or square lattice of springs at rest (in the
// limit of many particles: 4 k/m for a chain, in any direction).
#include "analysis_internal.h"

#include <math.h>
#include <stdbool.h>

// Off-diagonal entries at most this fraction of a matrix's largest entry count as converged in
// the Jacobi iteration: they move the eigenvalues by less than a thousandth of the round-off.
static const double jacobi_converged = 1e-19;

// Eigenvalues of the symmetric 3x3 matrix a (overwritten) by Jacobi rotations, and its
// eigenvectors as the columns of v if v is not NULL. Each rotation is orthogonal, so the
// eigenvalues carry an absolute error of a few eps times the largest entry, at any orientation.
// a must be finite.
static void symmetric_eigen(double a[3][3], double values[3], double v[3][3])
{
	double largest = 0.0;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			largest = fmax(largest, fabs(a[i][j]));
	if (v != NULL)
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++)
				v[i][j] = i == j ? 1.0 : 0.0;
	// Scaled to a largest entry of 1, so that no square below over- or underflows.
	const double scale = largest > 0.0 ? largest : 1.0;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			a[i][j] /= scale;
	static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
	// Cyclic Jacobi converges quadratically: three or four sweeps reach round-off.
	for (int sweep = 0; sweep < 50; sweep++) {
		if (fabs(a[0][1]) <= jacobi_converged && fabs(a[0][2]) <= jacobi_converged &&
		    fabs(a[1][2]) <= jacobi_converged)
			break;
		for (int k = 0; k < 3; k++) {
			const int p = pairs[k][0], q = pairs[k][1], r = 3 - p - q;
			if (a[p][q] == 0.0)
				continue;
			// The rotation in the (p, q) plane that zeroes a_pq: t = tan of its angle, the
			// smaller root of t^2 + 2 theta t - 1 = 0.
			const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
			const double t = fabs(theta) > 1e150
			                     ? 0.5 / theta
			                     : (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
			const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
			const double rp = a[r][p], rq = a[r][q];
			a[p][p] -= t * a[p][q];
			a[q][q] += t * a[p][q];
			a[p][q] = a[q][p] = 0.0;
			a[r][p] = a[p][r] = c * rp - s * rq;
			a[r][q] = a[q][r] = s * rp + c * rq;
			if (v != NULL)
				for (int i = 0; i < 3; i++) {
					const double vp = v[i][p], vq = v[i][q];
					v[i][p] = c * vp - s * vq;
					v[i][q] = s * vp + c * vq;
				}
		}
	}
	for (int i = 0; i < 3; i++)
		values[i] = a[i][i] * scale;
}

// Adds |S| + |w| I of the block b (its symmetric part S, its antisymmetric part W x = w x x) to
// upper and subtracts it from lower.
static void add_block_magnitude(double b[3][3], double upper[3][3], double lower[3][3])
{
	double s[3][3], values[3], v[3][3];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			s[i][j] = 0.5 * (b[i][j] + b[j][i]);
	symmetric_eigen(s, values, v);
	const double w =
	    hypot(hypot(0.5 * (b[1][2] - b[2][1]), 0.5 * (b[0][2] - b[2][0])), 0.5 * (b[0][1] - b[1][0]));
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) {
			double m = i == j ? w : 0.0;
			for (int k = 0; k < 3; k++)
				m += fabs(values[k]) * v[i][k] * v[j][k];
			upper[i][j] += m;
			lower[i][j] -= m;
		}
}

double sm_block_row_bound(const sm_block_row* row, const double* dof_mass)
{
	const size_t own = row->columns != NULL ? (size_t)row->columns[3 * row->diagonal] : 3 * row->diagonal;
	double upper[3][3] = {{0.0}}, lower[3][3] = {{0.0}};
	for (size_t k = 0; k < row->blocks; k++) {
		const size_t column = row->columns != NULL ? (size_t)row->columns[3 * k] : 3 * k;
		// The block of M^(-1/2) A M^(-1/2): entries over sqrt(m_p m_q), as for the scalar rows. The
		// masses are scaled by even powers of two first and the root back, exactly: m_p m_q would
		// be 0 for masses below 1e-154 kg and infinite above 1e154 kg.
		double divisor = 1.0;
		if (dof_mass != NULL) {
			const int p = ilogb(dof_mass[own]) / 2, q = ilogb(dof_mass[column]) / 2;
			divisor = scalbn(sqrt(scalbn(dof_mass[own], -2 * p) * scalbn(dof_mass[column], -2 * q)), p + q);
		}
		double b[3][3];
		bool zero = true;
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				const double entry = row->values[(size_t)i * row->stride + 3 * k + (size_t)j];
				b[i][j] = entry / divisor;
				if (!isfinite(b[i][j]))
					return INFINITY;
				zero = zero && entry == 0.0;
			}
		if (k == row->diagonal) {
			for (int i = 0; i < 3; i++)
				for (int j = 0; j < 3; j++) {
					upper[i][j] += 0.5 * (b[i][j] + b[j][i]);
					lower[i][j] += 0.5 * (b[i][j] + b[j][i]);
				}
		} else if (!zero) {
			add_block_magnitude(b, upper, lower);
		}
	}
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			if (!isfinite(upper[i][j]) || !isfinite(lower[i][j]))
				return INFINITY;
	double highest[3], lowest[3];
	symmetric_eigen(upper, highest, NULL);
	symmetric_eigen(lower, lowest, NULL);
	double bound = 0.0;
	for (int i = 0; i < 3; i++)
		bound = fmax(bound, fmax(highest[i], -lowest[i]));
	return bound;
}

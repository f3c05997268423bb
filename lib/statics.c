// Static equilibrium: Newton's method on the force balance with a line search on the potential
// energy.
//
// Unknowns are the positions x of the free particles (3 nf degrees of freedom). At zero
// velocity the force on the free particles is the negative gradient of the total potential
//
//   U(x) = sum_springs ks (L - l0)^2 / 2  -  sum_i (m_i g + f_ext,i) . x_i        [J]
//
// so f = -grad U and the exact Jacobian df/dx = -H, with H the Hessian of U (symmetric: the
// per-spring blocks of law_rest_length.h). Equilibrium is f(x) = 0.
//
// Newton step. p solves (H + mu M) p = f, with M the lumped masses and mu >= 0 [1/s^2] a shift:
// mu = 0 is Newton's method (quadratic convergence near a stable equilibrium); mu > 0 is an
// implicit dynamic-relaxation step with time step 1/sqrt(mu), which moves along the forces when
// H is indefinite or singular (a flat cloth has no transverse stiffness at its start; a
// pendulum-like rope may start far from hanging). Where H + mu M is indefinite the step is
// taken with the definiteness-preserving stiffness (compressive geometric terms dropped), and
// after ten such steps in a row with the exact H and mu raised until it factors. The dense path
// factors with GSL's modified Cholesky (gsl_linalg_mcholesky), which also perturbs an indefinite
// matrix into a positive definite one, so p is always a descent direction of U; the sparse path
// (CHOLMOD) raises mu until the factorisation succeeds.
//
// Line search. The step x + alpha p is accepted when U decreases enough (Armijo:
// dU <= 1e-4 alpha grad U . p). Near the solution the change of U is far below the round-off of
// U itself, so dU is computed directly as a sum of per-spring differences,
//   ks/2 [(L' - l0)^2 - (L - l0)^2] = ks/2 (L' - L)(L' + L - 2 l0),
//   L' - L = (d' - d) . (d' + d) / (L' + L),
// which keeps its relative accuracy down to the last step. mu shrinks after full steps and
// grows after short ones (a Levenberg-Marquardt rule), and grows tenfold when no step is found.
//
// No equilibrium. A group of free particles connected by springs but to no constrained particle
// is a free body; unless the net constant force on it is zero it accelerates for ever. That is
// checked first (union-find over the springs) and reported with the particles' indices, so the
// iteration never starts on a hopeless problem. Every loop is bounded by max_iterations.
#include "analysis_internal.h"
#include "model_internal.h"

#include <float.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_permutation.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef SPRINGMASS_HAVE_CHOLMOD
#include <cholmod.h>

#include "cholmod_factorize.h"
#endif

sm_statics_def sm_default_statics_def(void)
{
	sm_statics_def def;
	memset(&def, 0, sizeof def);
	def.start = NULL;
	def.external_forces = NULL;
	def.residual_tolerance = 0.0;  // automatic: SM_STATICS_DEFAULT_TOLERANCE, scaled to small loads
	def.max_iterations = 500;
	def.solver = SM_STATICS_AUTO;
	def.on_iteration = NULL;
	def.on_iteration_context = NULL;
	return def;
}

// ---------------------------------------------------------------------------------------------
// Work space of one solve.
// ---------------------------------------------------------------------------------------------

typedef struct statics_work {
	const sm_model* model;
	int32_t n, nf, ns;
	size_t dof;
	int32_t* free_index;     // n
	int32_t* free_particle;  // nf: particle of each free index
	double* dof_mass;        // dof [kg]
	int32_t* spring_a;       // ns
	int32_t* spring_b;
	double* rest_length;     // [m]
	double* stiffness;       // [N/m], 0 for disabled springs
	double* constant_force;  // 3 n: m g + load + f_ext [N]
	const double* external;  // 3 n or NULL
	// Each free particle's balance is judged against its own tolerance (docs/analysis.md):
	double* requested;     // nf: the tolerance asked for at each free particle [N]
	double* scale;         // nf: round-off scale of each free particle's balance (force_scale) [N]
	double requested_max;  // the largest of `requested` [N]
	double load;           // the largest constant force on a free particle [N]
	double* x;             // 3 n current positions
	double* y;             // 3 n trial positions
	double* f;             // 3 n forces
	double* rhs;           // dof
	double* step;          // dof
	double norm;           // largest row sum of |H + mu M| at the last factorisation [N/m]
	double dense_scale;    // dense path: the factor holds dense_scale (H + mu M) [1]
	// The caller's progress callback (sm_statics_def.on_iteration) and the iteration it last saw.
	bool (*on_iteration)(void* context, int32_t iterations, double residual);
	void* on_iteration_context;
	int32_t reported;
	// Dense path.
	double* matrix;        // dof x dof
	double* perturbation;  // dof
	size_t* permutation;   // dof
	// Sparse path.
	sm_sparse_jacobian* jacobian;
	double* values;     // nonzeros of H + mu M
	int64_t* diagonal;  // dof positions of the diagonal entries
#ifdef SPRINGMASS_HAVE_CHOLMOD
	cholmod_common common;
	int common_started;
	cholmod_factor* factor;
#endif
} statics_work;

static void work_free(statics_work* w)
{
	free(w->free_index);
	free(w->free_particle);
	free(w->dof_mass);
	free(w->spring_a);
	free(w->spring_b);
	free(w->rest_length);
	free(w->stiffness);
	free(w->constant_force);
	free(w->requested);
	free(w->scale);
	free(w->x);
	free(w->y);
	free(w->f);
	free(w->rhs);
	free(w->step);
	free(w->matrix);
	free(w->perturbation);
	free(w->permutation);
	sm_sparse_jacobian_destroy(w->jacobian);
	free(w->values);
	free(w->diagonal);
#ifdef SPRINGMASS_HAVE_CHOLMOD
	if (w->common_started) {
		if (w->factor != NULL)
			cholmod_l_free_factor(&w->factor, &w->common);
		cholmod_l_finish(&w->common);
	}
#endif
}

// Tells the caller's callback of an iteration not reported yet. False when it asks to stop (*st
// and err set).
static bool report_iteration(statics_work* w, const sm_statics_result* res, sm_status* st, sm_error* err)
{
	if (w->on_iteration == NULL || res->iterations == w->reported)
		return true;
	w->reported = res->iterations;
	if (w->on_iteration(w->on_iteration_context, res->iterations, res->residual))
		return true;
	*st =
	    sm_error_set(err, SM_ERROR_NOT_CONVERGED,
		             "statics: stopped by the caller (on_iteration) after %d iteration%s; the largest force "
		             "on a free particle is %.3g N",
		             (int)res->iterations, res->iterations == 1 ? "" : "s", res->residual);
	return false;
}

// Largest force component on free particle i [N] (NaN if any is).
static double particle_force(const statics_work* w, const double* f, int32_t i)
{
	const double* fi = f + 3 * (size_t)w->free_particle[i];
	double r = 0.0;
	for (int k = 0; k < 3; k++) {
		const double a = fabs(fi[k]);
		r = (a > r || isnan(a)) ? a : r;
	}
	return r;
}

// Largest force component on a free particle, each weighted by requested_max / its requested
// tolerance [N]: the measure whose halving the line search and the polish ask for. With one
// tolerance for every particle (a tolerance given, or loads of 1e-3 N and more) the weights are 1
// and it is the largest force component on a free particle, bit for bit; otherwise a light particle's force
// counts in proportion to how far it is from its own, smaller, tolerance.
static double weighted_residual(const statics_work* w, const double* f)
{
	double r = 0.0;
	for (int32_t i = 0; i < w->nf; i++) {
		const double force = particle_force(w, f, i);
		const double a =
		    force > 0.0 ? force * (w->requested_max / w->requested[i]) : force;  // 0, or NaN, as it is
		r = (a > r || isnan(a)) ? a : r;
	}
	return r;
}

// Whether every free particle's force is within the tolerance asked for at it (round-off floor
// aside).
static bool requested_met(const statics_work* w, const double* f)
{
	for (int32_t i = 0; i < w->nf; i++)
		if (!(particle_force(w, f, i) <= w->requested[i]))
			return false;
	return true;
}

// Round-off scale of the force balance at each free particle: every spring force is computed as
// ks (L - l0) from d = x_b - x_a, whose error is about eps ks max(L, l0, |x_a| + |x_b|), not
// eps |ks (L - l0)|: L and l0 are rounded relative to themselves, and d inherits the rounding
// of the positions, which are stored relative to the origin (a rope of 1 cm segments hanging
// 1 m below it: |x| is 100 times L). So the sum over the springs at a particle of
// ks max(L, l0, |x_a| + |x_b|), plus the constant force, bounds what round-off can leave in
// the balance there. Writes it for every free particle to w->scale [N]. It is the particle's
// own: the springs of a stiff part elsewhere do not enter the balance of a light part, which
// round-off resolves to its own scale (a separate block 1e9 times softer than a rope beside it).
static void force_scale(const statics_work* w, const double* x)
{
	double* s = w->scale;
	for (int32_t i = 0; i < w->nf; i++) {
		const double* c = w->constant_force + 3 * (size_t)w->free_particle[i];
		s[i] = hypot(hypot(c[0], c[1]), c[2]);
	}
	for (int32_t k = 0; k < w->ns; k++) {
		const double* xa = x + 3 * (size_t)w->spring_a[k];
		const double* xb = x + 3 * (size_t)w->spring_b[k];
		const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
		const double ra = sqrt(xa[0] * xa[0] + xa[1] * xa[1] + xa[2] * xa[2]);
		const double rb = sqrt(xb[0] * xb[0] + xb[1] * xb[1] + xb[2] * xb[2]);
		const double length = sqrt(dx * dx + dy * dy + dz * dz);
		const double t = w->stiffness[k] * fmax(fmax(length, w->rest_length[k]), ra + rb);
		const int32_t fa = w->free_index[w->spring_a[k]], fb = w->free_index[w->spring_b[k]];
		if (fa >= 0)
			s[fa] += t;
		if (fb >= 0)
			s[fb] += t;
	}
}

// The force balance f at x, particle by particle: free particle i is balanced when its largest
// force component is at most its tolerance, max(requested[i], SM_STATICS_ROUNDOFF_FACTOR eps
// scale[i]). Sets res->residual (the largest force component on a free particle), res->tolerance
// (the largest of the particles' tolerances, at least requested_max) and res->critical_* (the
// particle whose force is the largest fraction of its tolerance). Returns whether every free
// particle is balanced.
static bool assess(const statics_work* w, const double* x, const double* f, sm_statics_result* res)
{
	force_scale(w, x);
	double residual = 0.0, loosest = w->requested_max, worst = 0.0;
	bool balanced = true;
	res->critical_particle = -1;
	res->critical_residual = 0.0;
	res->critical_tolerance = 0.0;
	for (int32_t i = 0; i < w->nf; i++) {
		const double a = particle_force(w, f, i);
		const double tolerance =
		    fmax(w->requested[i], SM_STATICS_ROUNDOFF_FACTOR * DBL_EPSILON * w->scale[i]);
		residual = (a > residual || isnan(a)) ? a : residual;
		loosest = (tolerance > loosest || isnan(tolerance)) ? tolerance : loosest;
		if (!(a <= tolerance))
			balanced = false;
		const double ratio = a / tolerance;  // tolerance >= requested[i] > 0
		if (res->critical_particle < 0 || ratio > worst || (isnan(ratio) && !isnan(worst))) {
			worst = ratio;
			res->critical_particle = w->free_particle[i];
			res->critical_residual = a;
			res->critical_tolerance = tolerance;
		}
	}
	res->residual = residual;
	res->tolerance = loosest;
	return balanced;
}

// U(y) - U(x) [J], computed from differences so that it stays accurate when tiny; *roundoff
// gets the sum of the magnitudes of its terms [J].
static double energy_change(const statics_work* w, const double* x, const double* y, double* roundoff)
{
	double du = 0.0, mag = 0.0;
	for (int32_t k = 0; k < w->ns; k++) {
		if (w->stiffness[k] == 0.0)
			continue;
		const size_t a = 3 * (size_t)w->spring_a[k], b = 3 * (size_t)w->spring_b[k];
		double dd = 0.0, lx2 = 0.0, ly2 = 0.0;
		for (int c = 0; c < 3; c++) {
			const double dxc = x[b + c] - x[a + c];
			const double dyc = y[b + c] - y[a + c];
			const double change = (y[b + c] - x[b + c]) - (y[a + c] - x[a + c]);
			dd += change * (dyc + dxc);
			lx2 += dxc * dxc;
			ly2 += dyc * dyc;
		}
		const double lx = sqrt(lx2), ly = sqrt(ly2);
		const double dl = lx + ly > 0.0 ? dd / (lx + ly) : 0.0;
		const double term = 0.5 * w->stiffness[k] * dl * (ly + lx - 2.0 * w->rest_length[k]);
		du += term;
		mag += fabs(term);
	}
	for (int32_t i = 0; i < w->nf; i++) {
		const size_t p = 3 * (size_t)w->free_particle[i];
		for (int c = 0; c < 3; c++) {
			const double term = -w->constant_force[p + c] * (y[p + c] - x[p + c]);
			du += term;
			mag += fabs(term);
		}
	}
	*roundoff = mag;
	return du;
}

static double potential_energy(const statics_work* w, const double* x)
{
	sm_energies e = sm_model_energies(w->model, x, NULL);
	double u = e.elastic + e.gravity;
	if (w->external != NULL)
		for (size_t k = 0; k < 3 * (size_t)w->n; k++)
			u -= w->external[k] * x[k];
	return u;
}

// Free bodies: groups of particles joined by springs of non-zero stiffness that contain no
// constrained particle. Returns SM_OK, or SM_ERROR_NOT_CONVERGED with a message when the net
// constant force on such a group is not zero; *floating gets whether there is such a group (its
// translations cost no energy: any equilibrium is neutral, never stable).
static int32_t find_root(int32_t* parent, int32_t i)
{
	while (parent[i] != i) {
		parent[i] = parent[parent[i]];
		i = parent[i];
	}
	return i;
}

static sm_status check_free_bodies(const statics_work* w, bool* floating, sm_error* err)
{
	*floating = false;
	const int32_t n = w->n;
	int32_t* parent = malloc((size_t)n * sizeof *parent);
	double* net = calloc(3 * (size_t)n, sizeof *net);
	double* scale = calloc((size_t)n, sizeof *scale);
	int32_t* members = calloc((size_t)n, sizeof *members);
	unsigned char* held = calloc((size_t)n, 1);
	sm_status st = SM_OK;
	if (parent == NULL || net == NULL || scale == NULL || members == NULL || held == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory for %d particles", (int)n);
		goto done;
	}
	for (int32_t i = 0; i < n; i++)
		parent[i] = i;
	for (int32_t k = 0; k < w->ns; k++) {
		if (w->stiffness[k] == 0.0)
			continue;
		const int32_t ra = find_root(parent, w->spring_a[k]), rb = find_root(parent, w->spring_b[k]);
		if (ra != rb)
			parent[ra] = rb;
	}
	for (int32_t i = 0; i < n; i++) {
		const int32_t r = find_root(parent, i);
		members[r]++;
		if (w->free_index[i] < 0)
			held[r] = 1;
		const double* c = w->constant_force + 3 * (size_t)i;
		for (int k = 0; k < 3; k++)
			net[3 * (size_t)r + k] += c[k];
		scale[r] += hypot(hypot(c[0], c[1]), c[2]);
	}
	for (int32_t i = 0; i < n; i++) {
		if (parent[i] != i || held[i])
			continue;
		*floating = true;
		const double* F = net + 3 * (size_t)i;
		const double magnitude = hypot(hypot(F[0], F[1]), F[2]);  // no overflow for huge forces
		// The net force is a sum of members' forces: anything above its round-off is real.
		if (magnitude > 1e-12 * scale[i] && magnitude > 0.0) {
			int32_t first = -1;
			for (int32_t p = 0; p < n && first < 0; p++)
				if (find_root(parent, p) == i)
					first = p;
			st = sm_error_set(
			    err, SM_ERROR_NOT_CONVERGED,
			    "statics: no static equilibrium: particle %d and the %d other particle(s) joined to it "
			    "by springs of nonzero stiffness are held by no fixed or driven particle, yet feel a "
			    "net force (%g, %g, %g) N (gravity, loads and external forces); fix one of them (or drive it)",
			    (int)first, (int)members[i] - 1, F[0], F[1], F[2]);
			goto done;
		}
	}
done:
	free(parent);
	free(net);
	free(scale);
	free(members);
	free(held);
	return st;
}

// ---------------------------------------------------------------------------------------------
// Linear algebra: factor H + mu M and solve for the step. Returns 1 if the factorisation of
// the unmodified matrix succeeded (it was positive definite), 0 if it had to be modified
// (dense) or failed (sparse: no step), -1 on an internal failure.
// ---------------------------------------------------------------------------------------------

// Solves with the factor of the last factor_and_step (which returned 1): out = (H + mu M)^-1 rhs.
// Returns 0, or -1 on failure.
static int solve_factored(statics_work* w, const double* rhs, double* out)
{
#ifdef SPRINGMASS_HAVE_CHOLMOD
	if (w->jacobian != NULL)
		return sm_analysis_cholmod_solve(w->factor, &w->common, w->dof, rhs, out);
#endif
	gsl_matrix_view A = gsl_matrix_view_array(w->matrix, w->dof, w->dof);
	gsl_permutation perm = {w->dof, w->permutation};
	gsl_vector_const_view b = gsl_vector_const_view_array(rhs, w->dof);
	gsl_vector_view s = gsl_vector_view_array(out, w->dof);
	if (gsl_linalg_mcholesky_solve(&A.matrix, &perm, &b.vector, &s.vector) != GSL_SUCCESS)
		return -1;
	// (s A)^-1 rhs = A^-1 rhs / s.
	if (w->dense_scale != 1.0)
		for (size_t i = 0; i < w->dof; i++)
			out[i] *= w->dense_scale;
	return 0;
}

static int dense_step(statics_work* w, const double* x, double mu, sm_jacobian_variant variant,
                      const double* rhs, double* step)
{
	const size_t dof = w->dof;
	sm_analysis_dense_stiffness(w->model, w->free_index, x, dof, variant, w->matrix);
	for (size_t i = 0; i < dof; i++)
		w->matrix[i * dof + i] += mu * w->dof_mass[i];
	w->norm = 0.0;
	for (size_t i = 0; i < dof; i++) {
		double row = 0.0;
		for (size_t j = 0; j < dof; j++)
			row += fabs(w->matrix[i * dof + j]);
		w->norm = fmax(w->norm, row);
	}
	// GSL's modified Cholesky raises every pivot to at least DBL_EPSILON, an absolute floor in the
	// matrix's units [N/m]: a well-conditioned stiffness of springs below about 1e-16 N/m (a chain
	// of 1e-16 N/m zero-length springs between held ends) came out perturbed, so not positive
	// definite, unlike on the sparse path, and its steps were those of the floor. Scaled to a norm
	// of at least 1, the floor is at most DBL_EPSILON ||H + mu M||, relative like round-off; a
	// matrix of norm 1 or more is factored as it is.
	w->dense_scale = w->norm >= DBL_MIN && w->norm < 1.0 ? 1.0 / w->norm : 1.0;
	if (w->dense_scale != 1.0)
		for (size_t i = 0; i < dof * dof; i++)
			w->matrix[i] *= w->dense_scale;
	gsl_matrix_view A = gsl_matrix_view_array(w->matrix, dof, dof);
	gsl_permutation perm = {dof, w->permutation};
	gsl_vector_view E = gsl_vector_view_array(w->perturbation, dof);
	if (gsl_linalg_mcholesky_decomp(&A.matrix, &perm, &E.vector) != GSL_SUCCESS)
		return -1;
	int definite = 1;
	for (size_t i = 0; i < dof; i++)
		if (w->perturbation[i] != 0.0)
			definite = 0;
	if (step != NULL && solve_factored(w, rhs, step) != 0)
		return -1;
	return definite;
}

#ifdef SPRINGMASS_HAVE_CHOLMOD
static int sparse_prepare(statics_work* w)
{
	w->jacobian = sm_sparse_jacobian_create(w->model);
	if (w->jacobian == NULL)
		return -1;
	const int64_t nnz = sm_sparse_jacobian_nonzeros(w->jacobian);
	const int64_t dim = sm_sparse_jacobian_dimension(w->jacobian);
	if ((size_t)dim != w->dof)
		return -1;
	w->values = malloc((size_t)(nnz > 0 ? nnz : 1) * sizeof(double));
	w->diagonal = malloc(w->dof * sizeof(int64_t));
	if (w->values == NULL || w->diagonal == NULL)
		return -1;
	const int64_t* rows = sm_sparse_jacobian_row_pointers(w->jacobian);
	const int64_t* cols = sm_sparse_jacobian_column_indices(w->jacobian);
	for (int64_t r = 0; r < dim; r++) {
		w->diagonal[r] = -1;
		for (int64_t k = rows[r]; k < rows[r + 1]; k++)
			if (cols[k] == r)
				w->diagonal[r] = k;
		if (w->diagonal[r] < 0)
			return -1;
	}
	cholmod_l_start(&w->common);
	w->common_started = 1;
	w->common.print = 0;
	w->common.error_handler = NULL;
	// LL' stops at the first non-positive pivot, which is how an indefinite H + mu M is detected
	// (an LDL' would factor it with negative pivots): supernodal, or simplicial in LL' form
	// (final_ll). CHOLMOD picks between the two from its analysis (CHOLMOD_AUTO: supernodal from
	// 40 operations per entry of L): supernodal on sheets and blocks, simplicial on chains, whose
	// supernodes hold a few columns each (the statics of a swinging rope of 3000 - 20 000
	// segments 1.45 - 1.6 times faster: bench/README.md).
	w->common.supernodal = CHOLMOD_AUTO;
	w->common.final_ll = 1;
	return 0;
}

// The sparse pattern in CSR with a symmetric pattern is also its own CSC; CHOLMOD reads only
// the upper triangle (stype = 1).
static int sparse_step(statics_work* w, const double* x, double mu, sm_jacobian_variant variant,
                       const double* rhs, double* step)
{
	const sm_status fill = sm_sparse_jacobian_fill(w->jacobian, w->model, x, NULL, variant, w->values, NULL);
	if (fill != SM_OK)
		return fill == SM_ERROR_OUT_OF_MEMORY ? -2 : -1;
	const int64_t nnz = sm_sparse_jacobian_nonzeros(w->jacobian);
	for (int64_t k = 0; k < nnz; k++)
		w->values[k] = -w->values[k];
	for (size_t i = 0; i < w->dof; i++)
		w->values[w->diagonal[i]] += mu * w->dof_mass[i];
	const int64_t* rows = sm_sparse_jacobian_row_pointers(w->jacobian);
	w->norm = 0.0;
	for (size_t r = 0; r < w->dof; r++) {
		double row = 0.0;
		for (int64_t k = rows[r]; k < rows[r + 1]; k++)
			row += fabs(w->values[k]);
		w->norm = fmax(w->norm, row);
	}
	cholmod_sparse A = sm_analysis_cholmod_view(w->jacobian, w->dof, w->values);
	const int factored = sm_analysis_cholmod_factor(&A, &w->factor, &w->common);
	if (factored != 1 || step == NULL)
		return factored;
	return solve_factored(w, rhs, step) == 0 ? 1 : -1;
}
#endif

// Factors H + mu M and, if step is not NULL, solves for the step. Returns 1 if H + mu M is
// positive definite, 0 if not, -1 if the factorisation failed, -2 if the sparse Jacobian ran out
// of memory.
static int factor_and_step(statics_work* w, const double* x, double mu, sm_jacobian_variant variant,
                           const double* rhs, double* step)
{
#ifdef SPRINGMASS_HAVE_CHOLMOD
	if (w->jacobian != NULL)
		return sparse_step(w, x, mu, variant, rhs, step);
#endif
	return dense_step(w, x, mu, variant, rhs, step);
}

// The length of the longest inner product the last factorisation formed: the most nonzeros in a
// row of its factor L (H = L L^T; a row count of the sparse factor, in CHOLMOD's simplicial or
// supernodal form), or dof for the dense path. Cholesky's backward error grows with it: the factor
// is exact for H + E, |E| <= k eps |L| |L^T| / (1 - k eps) (Higham, Accuracy and Stability of
// Numerical Algorithms, 2nd ed., theorem 10.3, with n the inner products' length). dof where the
// counts cannot be had (out of memory), which only bounds it more loosely.
static size_t longest_factor_row(const statics_work* w)
{
	size_t longest = w->dof;
#ifdef SPRINGMASS_HAVE_CHOLMOD
	const cholmod_factor* L = w->jacobian != NULL ? w->factor : NULL;
	size_t* count = L != NULL ? calloc(w->dof + 1, sizeof *count) : NULL;
	if (count == NULL)
		return longest;
	if (L->is_super) {
		// Supernode s holds columns k1 to k2 - 1, all with the row pattern Ls[Lpi[s] ..]: a row
		// below the supernode's diagonal block is in all of its columns, row i within it in
		// columns k1 to i.
		const SuiteSparse_long *super = L->super, *pi = L->pi, *rows = L->s;
		for (size_t s = 0; s < L->nsuper; s++)
			for (SuiteSparse_long p = pi[s]; p < pi[s + 1]; p++) {
				const SuiteSparse_long i = rows[p];
				count[i] += (size_t)(i < super[s + 1] ? i - super[s] + 1 : super[s + 1] - super[s]);
			}
	} else {
		const SuiteSparse_long *start = L->p, *rows = L->i, *nonzeros = L->nz;
		for (size_t j = 0; j < L->n; j++)
			for (SuiteSparse_long p = start[j]; p < start[j] + nonzeros[j]; p++)
				count[rows[p]]++;
	}
	longest = 0;
	for (size_t i = 0; i < w->dof; i++)
		longest = count[i] > longest ? count[i] : longest;
	free(count);
#endif
	return longest;
}

// How far the round-off of the positions can move the stiffness along the unit vector v (over
// the free degrees of freedom) [N/m]. A rest-length spring's block is
//   K = ks u u^T + ks g (I - u u^T),   g = 1 - l0 / L,
// whose transverse, geometric part ks g = tension / L depends on L - l0. The positions fix L only
// to about eps max(L, l0, |x_a| + |x_b|) (force_scale: they are stored relative to the origin), so
// g only to dg = SM_STATICS_ROUNDOFF_FACTOR eps l0 max(L, l0, |x_a| + |x_b|) / L^2, the factor of
// the round-off floor. Where a spring's exact tension is zero (a bob on one spring without
// gravity, free to swing about its pin) the shape found leaves it a tension of that round-off and
// a geometric stiffness of either sign, which grows with the distance from the origin: 10 m from
// it, in one orientation in ten, that stiffness exceeded k eps ||H|| and the swinging bob was
// called stable. v^T K v changes by at most the sum over the springs of
// ks dg |(I - u u^T)(v_b - v_a)|^2 (v zero at held particles). Zero-length springs (ks I) and
// springs of rest length 0 have no such term; coincident particles are judged apart.
static double geometric_round_off(const statics_work* w, const double* v)
{
	double sum = 0.0;
	for (int32_t k = 0; k < w->ns; k++) {
		const double l0 = w->rest_length[k], ks = w->stiffness[k];
		const int32_t fa = w->free_index[w->spring_a[k]], fb = w->free_index[w->spring_b[k]];
		if (!(l0 > 0.0) || !(ks > 0.0) || (fa < 0 && fb < 0))
			continue;
		const double* xa = w->x + 3 * (size_t)w->spring_a[k];
		const double* xb = w->x + 3 * (size_t)w->spring_b[k];
		const double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
		const double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
		if (!(length > 0.0) || !isfinite(length))
			continue;
		const double ra = sqrt(xa[0] * xa[0] + xa[1] * xa[1] + xa[2] * xa[2]);
		const double rb = sqrt(xb[0] * xb[0] + xb[1] * xb[1] + xb[2] * xb[2]);
		const double dg = SM_STATICS_ROUNDOFF_FACTOR * DBL_EPSILON * l0 * fmax(fmax(length, l0), ra + rb) /
		                  (length * length);
		double r[3], along = 0.0, squared = 0.0;
		for (int c = 0; c < 3; c++) {
			r[c] = (fb >= 0 ? v[3 * (size_t)fb + c] : 0.0) - (fa >= 0 ? v[3 * (size_t)fa + c] : 0.0);
			along += r[c] * d[c] / length;
			squared += r[c] * r[c];
		}
		sum += ks * dg * fmax(0.0, squared - along * along);
	}
	return sum;
}

// Whether H, just factored as positive definite (factor_and_step at mu = 0 returned 1), is
// singular to working precision. A mechanism (a body free to turn about a pin, the sideways
// motion of a straight unstressed chain) has exact zero eigenvalues, which round-off leaves as
// pivots of either sign of about eps ||H||: a factorisation that succeeds does not prove H
// definite. Inverse iteration with the factor bounds the smallest eigenvalue from above:
// ||H^-1 v|| / ||v|| <= 1 / lambda_min, approached from below, and from a start with a component
// along a null vector it reaches about 1 / (eps ||H||) at the first solve. H counts as singular
// if lambda_min <= k eps ||H||_inf, k the longest inner product of the factorisation
// (longest_factor_row): below what the factor resolves (it is exact for H + E, whose error E moves
// the eigenvalues by up to about k eps ||H||). A sparse factor's k is its band or front, not dof: a
// 3000-segment hanging rope, with 9000 degrees of freedom and a lowest stiffness of 4e-3 N/m
// under ||H|| = 1.2e10 N/m, is resolved. To that threshold adds what the round-off of the
// positions can do to the stiffness along the vector found (geometric_round_off), so that a
// neutral motion counts as singular wherever the model sits. Returns 1 if singular, 0 if not, -1
// on failure.
static int singular_to_round_off(statics_work* w)
{
	const size_t dof = w->dof;
	double* v = w->rhs;
	double* y = w->step;
	// A start with components of both signs and varied sizes in every degree of freedom, the same
	// on every run (a fixed sequence, no random state).
	uint32_t state = 2463534242u;
	double length = 0.0;
	for (size_t i = 0; i < dof; i++) {
		state ^= state << 13;
		state ^= state >> 17;
		state ^= state << 5;
		v[i] = (double)state / 4294967296.0 - 0.5;
		length += v[i] * v[i];
	}
	double growth = 0.0;
	for (int iteration = 0; iteration < 3; iteration++) {
		if (solve_factored(w, v, y) != 0)
			return -1;
		double y_length = 0.0;
		for (size_t i = 0; i < dof; i++)
			y_length += y[i] * y[i];
		growth = sqrt(y_length / length);
		if (!(growth <= DBL_MAX))
			return 1;
		for (size_t i = 0; i < dof; i++)
			v[i] = y[i] / sqrt(y_length);
		length = 1.0;
	}
	return 1.0 / growth <= (double)longest_factor_row(w) * DBL_EPSILON * w->norm + geometric_round_off(w, v);
}

// Full Newton steps from w->x (every particle balanced, some only to its round-off floor, above
// the tolerance asked for there) while each at least halves the weighted residual and keeps every
// particle balanced, within the iterations up to `last`: the floor bounds the round-off of the
// force balance from above, and a shape within it can still carry the same unbalanced force at
// every particle (a stiff rope left by the stiffness continuation 2.4 % off its weight at every
// particle, under a floor of 2.9 %). Leaves w->f the forces at w->x. False on a fatal error (*st
// and err set).
static bool polish(statics_work* w, int32_t last, sm_statics_result* res, sm_status* st, sm_error* err)
{
	const size_t n3 = 3 * (size_t)w->n;
	double weighted = weighted_residual(w, w->f);
	while (!requested_met(w, w->f) && res->iterations < last) {
		for (int32_t i = 0; i < w->nf; i++)
			memcpy(w->rhs + 3 * (size_t)i, w->f + 3 * (size_t)w->free_particle[i], 3 * sizeof(double));
		const int factored = factor_and_step(w, w->x, 0.0, SM_JACOBIAN_EXACT, w->rhs, w->step);
		if (factored == -2) {
			*st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory at iteration %d",
			                   (int)res->iterations);
			return false;
		}
		if (factored != 1 || !sm_analysis_all_finite(w->step, w->dof))
			return true;
		memcpy(w->y, w->x, n3 * sizeof(double));
		for (int32_t i = 0; i < w->nf; i++)
			for (int c = 0; c < 3; c++)
				w->y[3 * (size_t)w->free_particle[i] + c] += w->step[3 * (size_t)i + c];
		sm_model_forces(w->model, w->y, NULL, w->external, w->f);
		const double next = weighted_residual(w, w->f);
		sm_statics_result trial = *res;
		if (!(next < 0.5 * weighted) || !assess(w, w->y, w->f, &trial)) {
			sm_model_forces(w->model, w->x, NULL, w->external, w->f);
			return true;
		}
		memcpy(w->x, w->y, n3 * sizeof(double));
		*res = trial;
		weighted = next;
		res->iterations++;
		if (!report_iteration(w, res, st, err))
			return false;
	}
	return true;
}

// Definite steps after which the exact stiffness is tried with a larger shift. The definite
// stiffness drops the compressive geometric terms, and its steps converge only linearly where
// those terms shape the solution: the softest continuation stage of the 64 x 64 benchmark cloth
// (a hem that wrinkles) spent 210 such steps at 2.4 % each, with the exact H indefinite by about
// 5e-7 mu_ref, so that H + mu M factors once mu exceeds that. Its steps, downhill like every step
// from a positive definite matrix, keep the compressive terms and reach the region where H itself
// is definite within 10 iterations (386 -> 214 iterations in all, the same rest shape). Runs of
// fewer definite steps, the usual way out of a compressed start, are left as they were.
#define DEFINITE_RUN 10

// Newton's method from w->x on w->model (whose spring stiffnesses are in w->stiffness), for at
// most `budget` iterations (counted in res->iterations). Returns 1 when converged, 0 when the
// budget ran out or no descent step was found (the caller may try another way), -1 on a fatal
// error (*st and err set).
static int newton(statics_work* w, int32_t budget, sm_statics_result* res, sm_status* st, sm_error* err)
{
	const sm_model* model = w->model;
	const size_t n3 = 3 * (size_t)w->n;
	// Reference for the shift: the largest spring stiffness per unit mass at a particle,
	// sum ks / m [1/s^2] (the square of the stiffest local frequency).
	double mu_ref = 0.0;
	{
		double* s = w->rhs;
		memset(s, 0, w->dof * sizeof(double));
		for (int32_t k = 0; k < w->ns; k++) {
			const int32_t fa = w->free_index[w->spring_a[k]], fb = w->free_index[w->spring_b[k]];
			if (fa >= 0)
				s[fa] += w->stiffness[k];
			if (fb >= 0)
				s[fb] += w->stiffness[k];
		}
		for (int32_t i = 0; i < w->nf; i++)
			mu_ref = fmax(mu_ref, s[i] / w->dof_mass[3 * (size_t)i]);
		if (!(mu_ref > 0.0))
			mu_ref = 1.0;
	}
	const int32_t last = res->iterations + budget;
	double mu = 0.0;
	int definite_steps = 0;  // consecutive iterations that took the definite stiffness
	const double armijo = 1e-4;
	for (;;) {
		sm_model_forces(model, w->x, NULL, w->external, w->f);
		const bool balanced = assess(w, w->x, w->f, res);
		const double weighted = weighted_residual(w, w->f);
		if (!isfinite(res->residual)) {
			*st = sm_error_set(err, SM_ERROR_NOT_FINITE,
			                   "statics: the forces became non-finite at iteration %d", (int)res->iterations);
			return -1;
		}
		// Stiffness times distance beyond the largest double: no force balance can be told there.
		if (!isfinite(res->tolerance)) {
			*st = sm_error_set(
			    err, SM_ERROR_NOT_FINITE,
			    "statics: the spring forces' round-off scale (stiffness x distance) overflows at "
			    "iteration %d",
			    (int)res->iterations);
			return -1;
		}
		if (!report_iteration(w, res, st, err))
			return -1;
		// Where the loosest floor exceeds every load, no balance resolves the loads (the solve is
		// refused: sm_statics_solve), and a particle's own tolerance is not worth chasing further.
		const bool unresolvable = res->residual <= res->tolerance && res->tolerance > w->requested_max &&
		                          w->load > 0.0 && res->tolerance > w->load;
		if (balanced || unresolvable) {
			if (!requested_met(w, w->f) && !polish(w, last, res, st, err))
				return -1;
			assess(w, w->x, w->f, res);
			return 1;
		}
		if (res->iterations >= last)
			return 0;
		res->iterations++;
		for (int32_t i = 0; i < w->nf; i++)
			memcpy(w->rhs + 3 * (size_t)i, w->f + 3 * (size_t)w->free_particle[i], 3 * sizeof(double));
		int factored = factor_and_step(w, w->x, mu, SM_JACOBIAN_EXACT, w->rhs, w->step);
		// After DEFINITE_RUN definite steps in a row, the exact H with a larger shift first: mu
		// grows tenfold from max(10 mu, 1e-9 mu_ref) until H + mu M factors, up to 1e-3 mu_ref (the
		// shift found then shrinks after full steps, as any).
		for (double m = fmax(10.0 * mu, 1e-9 * mu_ref);
		     factored == 0 && definite_steps >= DEFINITE_RUN && m <= 1e-3 * mu_ref; m *= 10.0) {
			factored = factor_and_step(w, w->x, m, SM_JACOBIAN_EXACT, w->rhs, w->step);
			if (factored == 1)
				mu = m;
		}
		definite_steps = factored == 0 ? definite_steps + 1 : 0;
		if (factored == 0) {
			// Indefinite (compressed springs, a shape far from the rest shape): the
			// definiteness-preserving stiffness, with compressive geometric terms dropped, is
			// positive semi-definite, and with the shift a descent direction of U.
			factored =
			    factor_and_step(w, w->x, fmax(mu, 1e-9 * mu_ref), SM_JACOBIAN_DEFINITE, w->rhs, w->step);
		}
		if (factored == -2) {
			*st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory at iteration %d",
			                   (int)res->iterations);
			return -1;
		}
		if (factored < 0) {
			*st = sm_error_set(err, SM_ERROR_SOLVER, "statics: the linear solver failed at iteration %d",
			                   (int)res->iterations);
			return -1;
		}
		const int have_step = factored > 0 || w->jacobian == NULL;
		double slope = 0.0;  // grad U . p = -f . p
		if (have_step)
			for (size_t k = 0; k < w->dof; k++)
				slope -= w->rhs[k] * w->step[k];
		int accepted = 0;
		double alpha = 1.0;
		if (have_step && slope < 0.0 && sm_analysis_all_finite(w->step, w->dof)) {
			for (int tries = 0; tries < 40 && !accepted; tries++, alpha *= 0.5) {
				memcpy(w->y, w->x, n3 * sizeof(double));
				for (int32_t i = 0; i < w->nf; i++)
					for (int c = 0; c < 3; c++)
						w->y[3 * (size_t)w->free_particle[i] + c] += alpha * w->step[3 * (size_t)i + c];
				double roundoff = 0.0;
				const double du = energy_change(w, w->x, w->y, &roundoff);
				if (isfinite(du) && du <= armijo * alpha * slope + 64.0 * DBL_EPSILON * roundoff)
					accepted = 1;
			}
			alpha *= 2.0;  // undo the last halving
			if (!accepted) {
				// At the round-off level of U the Armijo test is blind; the full Newton step is
				// still taken if it shrinks the force residual decisively.
				memcpy(w->y, w->x, n3 * sizeof(double));
				for (int32_t i = 0; i < w->nf; i++)
					for (int c = 0; c < 3; c++)
						w->y[3 * (size_t)w->free_particle[i] + c] += w->step[3 * (size_t)i + c];
				sm_model_forces(model, w->y, NULL, w->external, w->f);
				if (weighted_residual(w, w->f) < 0.5 * weighted) {
					accepted = 1;
					alpha = 1.0;
				}
			}
		}
		if (accepted) {
			memcpy(w->x, w->y, n3 * sizeof(double));
			if (alpha == 1.0)
				mu = mu < 1e-9 * mu_ref ? 0.0 : 0.25 * mu;
			else if (alpha < 0.25)
				mu = mu == 0.0 ? 1e-6 * mu_ref : 10.0 * mu;
		} else {
			mu = mu == 0.0 ? 1e-6 * mu_ref : 10.0 * mu;
			if (mu > 1e12 * mu_ref)  // giving up: the iteration left the shape where it was
				return report_iteration(w, res, st, err) ? 0 : -1;
		}
	}
}

// Sets the stiffness of every spring of w->model (a clone) to scale times the original's.
static sm_status scale_stiffness(statics_work* w, sm_model* clone, const sm_model* original, double scale)
{
	for (int32_t k = 0; k < w->ns; k++) {
		sm_spring_def sd;
		sm_model_get_spring(original, k, &sd);
		sd.stiffness *= scale;
		const sm_status st = sm_model_set_spring(clone, k, &sd);
		if (st != SM_OK)
			return st;
		double l0 = 0.0, ks = 0.0, kd = 0.0;
		sm_model_spring_constants(clone, k, &l0, &ks, &kd);
		w->stiffness[k] = sm_model_spring_enabled(clone, k) ? ks : 0.0;
	}
	return SM_OK;
}

// Newton's method, and if it does not converge within 50 iterations, continuation
// in the stiffness: nearly inextensible cables and stiff cloth make U a narrow curved valley in
// which Newton's steps stay short for hundreds of iterations. Softened by a factor s, the same
// structure sags into a shape with strains of order one, where Newton converges at once; s then
// grows tenfold per stage, each stage starting from the previous equilibrium, up to s = 1 (the
// real model). A stage that fails is retried from the last good shape with a smaller growth.
static sm_status solve_with_continuation(statics_work* w, const sm_statics_def* d, sm_statics_result* res,
                                         int* converged, sm_error* err)
{
	sm_status st = SM_OK;
	const int32_t first_budget = d->max_iterations < 100 ? d->max_iterations : 50;
	const int r = newton(w, first_budget, res, &st, err);
	if (r != 0 || w->ns == 0 || res->iterations >= d->max_iterations) {
		*converged = r == 1;
		return r < 0 ? st : SM_OK;
	}
	const sm_model* original = w->model;
	const size_t n3 = 3 * (size_t)w->n;
	sm_model* clone = sm_model_clone(original);
	double* saved = malloc((n3 + 1) * sizeof(double));
	double* original_stiffness = malloc(((size_t)w->ns + 1) * sizeof(double));
	if (clone == NULL || saved == NULL || original_stiffness == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory for the continuation");
		goto done;
	}
	memcpy(original_stiffness, w->stiffness, (size_t)w->ns * sizeof(double));
	if (d->start != NULL)
		memcpy(w->x, d->start, n3 * sizeof(double));
	else
		sm_model_initial_state(original, w->x, NULL);
	// Softest stage: spring forces ks l at the scale of the constant load.
	double load = 0.0, spring = 0.0;
	for (int32_t i = 0; i < w->nf; i++) {
		const double* c = w->constant_force + 3 * (size_t)w->free_particle[i];
		load += sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
	}
	for (int32_t k = 0; k < w->ns; k++) {
		const double* xa = w->x + 3 * (size_t)w->spring_a[k];
		const double* xb = w->x + 3 * (size_t)w->spring_b[k];
		const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
		const double length = fmax(w->rest_length[k], sqrt(dx * dx + dy * dy + dz * dz));
		spring = fmax(spring, w->stiffness[k] * length);
	}
	double scale = spring > 0.0 ? fmin(0.1, fmax(1e-12, load / spring)) : 1.0;
	double good = 0.0, growth = 10.0;
	int softenings = 0;
	memcpy(saved, w->x, n3 * sizeof(double));
	for (;;) {
		const int final_stage = scale >= 1.0;
		if (final_stage) {
			w->model = original;
			memcpy(w->stiffness, original_stiffness, (size_t)w->ns * sizeof(double));
		} else {
			if ((st = scale_stiffness(w, clone, original, scale)) != SM_OK) {
				sm_error_set(err, st, "statics: cannot soften the springs: %s", sm_model_last_error(clone));
				goto done;
			}
			w->model = clone;
		}
		const int32_t remaining = d->max_iterations - res->iterations;
		if (remaining <= 0)
			break;
		// A stage gets every iteration left: one that stalls (newton gives up when its shift grows
		// past any use) leaves the rest to a retry with smaller growth, and one that converges
		// slowly is not cut short (a cap of a quarter of max_iterations made the 64 x 64 benchmark
		// cloth fail at the default 500, which then took 386 in all; a slack chain of 2000 segments
		// started straight, 273).
		const int c = newton(w, remaining, res, &st, err);
		if (c < 0)
			goto done;
		if (c == 1) {
			if (final_stage) {
				*converged = 1;
				break;
			}
			good = scale;
			memcpy(saved, w->x, n3 * sizeof(double));
			scale = fmin(1.0, scale * growth);
		} else if (good == 0.0) {
			// Even the softest stage failed: soften further, at most three times.
			memcpy(w->x, saved, n3 * sizeof(double));
			if (++softenings > 3)
				break;
			scale *= 0.01;
		} else {
			memcpy(w->x, saved, n3 * sizeof(double));
			growth = sqrt(growth);
			if (growth < 1.01)
				break;
			scale = fmin(1.0, good * growth);
		}
	}
done:
	w->model = original;
	if (original_stiffness != NULL)
		memcpy(w->stiffness, original_stiffness, (size_t)w->ns * sizeof(double));
	if (st == SM_OK && !*converged) {
		sm_model_forces(original, w->x, NULL, w->external, w->f);
		assess(w, w->x, w->f, res);
	}
	sm_model_destroy(clone);
	free(saved);
	free(original_stiffness);
	return st;
}

// ---------------------------------------------------------------------------------------------

static sm_status work_init(statics_work* w, const sm_model* model, const sm_statics_def* def, sm_error* err)
{
	memset(w, 0, sizeof *w);
	w->model = model;
	w->n = sm_model_particle_count(model);
	w->ns = sm_model_spring_count(model);
	w->external = def->external_forces;
	w->on_iteration = def->on_iteration;
	w->on_iteration_context = def->on_iteration_context;
	w->dense_scale = 1.0;
	const size_t n3 = 3 * (size_t)w->n;
	w->free_index = malloc(((size_t)w->n + 1) * sizeof(int32_t));
	w->dof_mass = malloc((n3 + 1) * sizeof(double));
	if (w->free_index == NULL || w->dof_mass == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory for %d particles",
		                    (int)w->n);
	w->nf = sm_analysis_free_map(model, w->free_index, w->dof_mass);
	w->dof = 3 * (size_t)w->nf;
	const size_t ns = (size_t)w->ns + 1, dof = w->dof + 1;
	w->free_particle = malloc(((size_t)w->nf + 1) * sizeof(int32_t));
	w->spring_a = malloc(ns * sizeof(int32_t));
	w->spring_b = malloc(ns * sizeof(int32_t));
	w->rest_length = malloc(ns * sizeof(double));
	w->stiffness = malloc(ns * sizeof(double));
	w->constant_force = malloc((n3 + 1) * sizeof(double));
	w->x = malloc((n3 + 1) * sizeof(double));
	w->y = malloc((n3 + 1) * sizeof(double));
	w->f = malloc((n3 + 1) * sizeof(double));
	w->rhs = malloc(dof * sizeof(double));
	w->step = malloc(dof * sizeof(double));
	w->requested = malloc(((size_t)w->nf + 1) * sizeof(double));
	w->scale = malloc(((size_t)w->nf + 1) * sizeof(double));
	if (w->free_particle == NULL || w->spring_a == NULL || w->spring_b == NULL || w->rest_length == NULL ||
	    w->stiffness == NULL || w->constant_force == NULL || w->x == NULL || w->y == NULL || w->f == NULL ||
	    w->rhs == NULL || w->step == NULL || w->requested == NULL || w->scale == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory for %d particles",
		                    (int)w->n);
	for (int32_t p = 0; p < w->n; p++)
		if (w->free_index[p] >= 0)
			w->free_particle[w->free_index[p]] = p;
	for (int32_t k = 0; k < w->ns; k++) {
		sm_spring_def sd;
		double l0 = 0.0, ks = 0.0, kd = 0.0;
		sm_model_get_spring(model, k, &sd);
		sm_model_spring_constants(model, k, &l0, &ks, &kd);
		w->spring_a[k] = sd.a;
		w->spring_b[k] = sd.b;
		w->rest_length[k] = l0;
		w->stiffness[k] = sm_model_spring_enabled(model, k) ? ks : 0.0;
	}
	const sm_model_def md = sm_model_get_def(model);
	for (int32_t p = 0; p < w->n; p++) {
		sm_particle_def pd;
		sm_model_get_particle(model, p, &pd);
		for (int c = 0; c < 3; c++)
			w->constant_force[3 * (size_t)p + c] =
			    pd.mass * md.gravity[c] + pd.load[c] +
			    (w->external != NULL ? w->external[3 * (size_t)p + c] : 0.0);
	}
	if (def->start != NULL)
		memcpy(w->x, def->start, n3 * sizeof(double));
	else
		sm_model_initial_state(model, w->x, NULL);
	return SM_OK;
}

static sm_status setup_solver(statics_work* w, sm_statics_solver* solver, sm_error* err)
{
	if (*solver == SM_STATICS_AUTO)
		*solver = w->dof <= SM_STATICS_DENSE_LIMIT ? SM_STATICS_DENSE : SM_STATICS_SPARSE;
#ifndef SPRINGMASS_HAVE_CHOLMOD
	if (*solver == SM_STATICS_SPARSE) {
		if (w->dof > 3 * SM_STATICS_DENSE_LIMIT)
			return sm_error_set(
			    err, SM_ERROR_INVALID_ARGUMENT,
			    "statics: %zu degrees of freedom need the sparse solver, which this build lacks "
			    "(CHOLMOD)",
			    w->dof);
		*solver = SM_STATICS_DENSE;
	}
#endif
	if (*solver == SM_STATICS_DENSE) {
		const size_t dof = w->dof + 1;
		if (dof > 0 && dof > SIZE_MAX / sizeof(double) / dof)
			return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
			                    "statics: dense matrix of %zu unknowns too large", w->dof);
		w->matrix = malloc(dof * dof * sizeof(double));
		w->perturbation = malloc(dof * sizeof(double));
		w->permutation = malloc(dof * sizeof(size_t));
		if (w->matrix == NULL || w->perturbation == NULL || w->permutation == NULL)
			return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
			                    "statics: out of memory for a dense %zu x %zu matrix (use the sparse solver)",
			                    w->dof, w->dof);
	}
#ifdef SPRINGMASS_HAVE_CHOLMOD
	if (*solver == SM_STATICS_SPARSE && sparse_prepare(w) != 0)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: cannot set up the sparse factorisation");
#endif
	return SM_OK;
}

// The tolerance asked for at each free particle: `given` (residual_tolerance > 0) at every one; by
// default SM_STATICS_DEFAULT_TOLERANCE, or SM_STATICS_LOAD_FRACTION of the particle's own constant
// force (weight, load, external force) where that is smaller, so that a light part's balance is
// judged against its own weight, not against the heaviest particle's (a 1e-9 kg block beside a
// 1 kg rope: 1e-6 of the rope's particles' weight is tens of times the block's particles').
// A particle without a constant force of its own (no gravity) takes the largest of the free
// particles joined to it by springs through free particles, whose loads its springs carry, and
// failing any, the largest on a free particle, `load` [N]. With no load anywhere, the default.
// `tolerance` is the one resolved for the whole model (the given one, or the default for `load`),
// the largest of them.
static sm_status set_requested_tolerances(statics_work* w, bool given, double tolerance, double load,
                                          sm_error* err)
{
	double* own = w->scale;  // scratch, nf entries
	for (int32_t i = 0; i < w->nf; i++) {
		const double* c = w->constant_force + 3 * (size_t)w->free_particle[i];
		own[i] = hypot(hypot(c[0], c[1]), c[2]);
	}
	bool unloaded = false;
	for (int32_t i = 0; i < w->nf; i++)
		unloaded = unloaded || !(own[i] > 0.0);
	if (!given && load > 0.0 && unloaded) {
		int32_t* parent = malloc(((size_t)w->nf + 1) * sizeof *parent);
		double* group = malloc(((size_t)w->nf + 1) * sizeof *group);
		if (parent == NULL || group == NULL) {
			free(parent);
			free(group);
			return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "statics: out of memory for %d particles",
			                    (int)w->n);
		}
		for (int32_t i = 0; i < w->nf; i++) {
			parent[i] = i;
			group[i] = 0.0;
		}
		for (int32_t k = 0; k < w->ns; k++) {
			const int32_t fa = w->free_index[w->spring_a[k]], fb = w->free_index[w->spring_b[k]];
			if (w->stiffness[k] == 0.0 || fa < 0 || fb < 0)
				continue;
			const int32_t ra = find_root(parent, fa), rb = find_root(parent, fb);
			if (ra != rb)
				parent[ra] = rb;
		}
		for (int32_t i = 0; i < w->nf; i++) {
			const int32_t r = find_root(parent, i);
			group[r] = fmax(group[r], own[i]);
		}
		for (int32_t i = 0; i < w->nf; i++)
			if (!(own[i] > 0.0)) {
				const double g = group[find_root(parent, i)];
				own[i] = g > 0.0 ? g : load;
			}
		free(parent);
		free(group);
	}
	// The particle of the largest load takes `tolerance` itself: it stays the largest.
	w->requested_max = tolerance;
	for (int32_t i = 0; i < w->nf; i++) {
		double t = tolerance;
		if (!given && load > 0.0)
			t = fmin(SM_STATICS_DEFAULT_TOLERANCE, SM_STATICS_LOAD_FRACTION * own[i]);
		w->requested[i] = t > 0.0 ? t : DBL_TRUE_MIN;  // a load so small that its fraction underflows
		w->requested_max = fmax(w->requested_max, w->requested[i]);
	}
	return SM_OK;
}

sm_status sm_statics_solve(const sm_model* model, const sm_statics_def* def, double* x, double* reactions,
                           sm_statics_result* result, sm_error* err)
{
	sm_statics_result res;
	memset(&res, 0, sizeof res);
	res.coincident_spring = -1;
	res.critical_particle = -1;  // none until a balance is judged
	if (result != NULL)
		*result = res;
	sm_statics_def d = def != NULL ? *def : sm_default_statics_def();
	if (model == NULL || x == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "statics: model and x must not be NULL");
	if (!(d.residual_tolerance >= 0.0) || !isfinite(d.residual_tolerance))
		return sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "statics: residual_tolerance must be finite and > 0 N (0 for the default), got %g",
		    d.residual_tolerance);
	if (d.max_iterations < 1)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "statics: max_iterations must be >= 1, got %d",
		                    (int)d.max_iterations);
	if (d.solver != SM_STATICS_AUTO && d.solver != SM_STATICS_DENSE && d.solver != SM_STATICS_SPARSE)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "statics: unknown solver %d", (int)d.solver);
	const size_t n3 = 3 * (size_t)sm_model_particle_count(model);
	if (d.start != NULL)
		for (size_t k = 0; k < n3; k++)
			if (!isfinite(d.start[k]))
				return sm_error_set(err, SM_ERROR_NOT_FINITE,
				                    "statics: start position of particle %zu is not finite", k / 3);
	if (d.external_forces != NULL)
		for (size_t k = 0; k < n3; k++)
			if (!isfinite(d.external_forces[k]))
				return sm_error_set(err, SM_ERROR_NOT_FINITE,
				                    "statics: external force on particle %zu is not finite", k / 3);

	statics_work w;
	sm_status st = work_init(&w, model, &d, err);
	bool floating = false;
	if (st == SM_OK)
		st = check_free_bodies(&w, &floating, err);
	if (st == SM_OK)
		st = setup_solver(&w, &d.solver, err);
	if (st != SM_OK) {
		work_free(&w);
		return st;
	}
	res.solver = d.solver;
	// The largest constant force on a free particle (its weight, load and external force) sets the
	// scale of the balance. A tolerance in newtons fixed for metre-and-kilogram models passes any
	// shape of a model whose loads lie below it (a 1e-12 kg proof mass weighs 9.8e-12 N, a
	// hundredth of 1e-9 N): the default is scaled down to SM_STATICS_LOAD_FRACTION of the load
	// there, and a tolerance given at or above the load is refused.
	double load = 0.0;
	for (int32_t i = 0; i < w.nf; i++) {
		const double* c = w.constant_force + 3 * (size_t)w.free_particle[i];
		load = fmax(load, hypot(hypot(c[0], c[1]), c[2]));
	}
	const bool given = d.residual_tolerance > 0.0;
	if (!given) {
		d.residual_tolerance = SM_STATICS_DEFAULT_TOLERANCE;
		if (load > 0.0)
			d.residual_tolerance = fmin(d.residual_tolerance, SM_STATICS_LOAD_FRACTION * load);
	} else if (load > 0.0 && d.residual_tolerance >= load) {
		work_free(&w);
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "statics: residual_tolerance %.3g N is not below the largest load on a free "
		                    "particle, %.3g N: any shape would pass as a rest shape",
		                    d.residual_tolerance, load);
	}
	if ((st = set_requested_tolerances(&w, given, d.residual_tolerance, load, err)) != SM_OK) {
		work_free(&w);
		return st;
	}
	d.residual_tolerance = w.requested_max;  // the loosest particle's
	w.load = load;

	int converged = 0;
	st = solve_with_continuation(&w, &d, &res, &converged, err);
	// Either the iterations ran out, or the stiffness continuation stopped before: no stage it could
	// reach converged (a load far beyond what the springs carry, a model with no equilibrium). A
	// message puts no value right after "particle", which reads as a particle's index (springmass
	// statics adds that particle's name to "particle 20").
	const bool gave_up = st == SM_OK && !converged;
	if (gave_up) {
		// What is left: the largest force above every tolerance, or a particle above its own,
		// smaller, one (a light part whose balance the heavy part's tolerance does not resolve).
		char left[200];
		if (res.residual > res.tolerance || res.critical_particle < 0)
			sm_format_c_locale(left, sizeof left,
			                   "the largest force on a free particle is %.3g N > tolerance %.3g N",
			                   res.residual, res.tolerance);
		else
			sm_format_c_locale(
			    left, sizeof left,
			    "particle %d carries %.3g N > its own tolerance %.3g N (the largest force on a free "
			    "particle is %.3g N)",
			    (int)res.critical_particle, res.critical_residual, res.critical_tolerance, res.residual);
		if (res.iterations >= d.max_iterations)
			st = sm_error_set(err, SM_ERROR_NOT_CONVERGED,
			                  "statics: no equilibrium found in %d iteration%s (max_iterations): %s",
			                  (int)res.iterations, res.iterations == 1 ? "" : "s", left);
		else
			st = sm_error_set(
			    err, SM_ERROR_NOT_CONVERGED,
			    "statics: no equilibrium found: the stiffness continuation gave up after %d of at "
			    "most %d iterations, no softened stage converging; %s",
			    (int)res.iterations, (int)d.max_iterations, left);
	}

	for (int c = 0; c < 3; c++)
		res.reaction_total[c] = 0.0;
	for (int32_t p = 0; p < w.n; p++)
		if (w.free_index[p] < 0)
			for (int c = 0; c < 3; c++)
				res.reaction_total[c] -= w.f[3 * (size_t)p + c];
	res.potential_energy = potential_energy(&w, w.x);
	// Stable if the exact stiffness is positive definite beyond round-off (it factors, and it is
	// not singular to working precision) and no group of particles floats free; out of memory for
	// the sparse Jacobian, it cannot be told.
	int definite = 1;
	if (converged && w.nf > 0 && !floating) {
		definite = factor_and_step(&w, w.x, 0.0, SM_JACOBIAN_EXACT, NULL, NULL);
		if (definite == 1) {
			const int singular = singular_to_round_off(&w);
			definite = singular < 0 ? -1 : !singular;
		}
	}
	// The round-off floor is evaluated where the iteration ends, and grows with the distance of
	// the particles from the origin: an iteration carried far away (a stiffness contrast that the
	// continuation softens until the soft springs stretch a billion times their length) meets it
	// with any shape. A balance whose floor exceeds every load cannot tell the loads from
	// round-off: no rest shape is resolved there, whatever the residual; and an iteration that gave
	// up there with every force within the loosest tolerance (some particle still above its own,
	// smaller, one) failed for that reason.
	const bool within_loosest = gave_up && res.residual <= res.tolerance;
	if ((converged || within_loosest) && load > 0.0 && res.tolerance > d.residual_tolerance &&
	    res.tolerance > load) {
		converged = 0;
		st = sm_error_set(
		    err, SM_ERROR_NOT_CONVERGED,
		    "statics: no rest shape can be resolved: the round-off of the spring forces (stiffness "
		    "x position rounding) is %.3g N where the iteration ended, above the largest load on a "
		    "particle, %.3g N (a stiffness contrast beyond double precision at these coordinates)",
		    res.tolerance, load);
	}
	if (definite == -2) {
		converged = 0;
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		                  "statics: out of memory for the Jacobian of the stability test");
	}
	if (converged) {
		res.coincident_spring = sm_analysis_coincident_spring(model, w.x);
		res.stable = definite == 1 && !floating && res.coincident_spring < 0;
		memcpy(x, w.x, n3 * sizeof(double));
		if (reactions != NULL)
			for (int32_t p = 0; p < w.n; p++)
				for (int c = 0; c < 3; c++)
					reactions[3 * (size_t)p + c] =
					    w.free_index[p] < 0 ? 0.0 - w.f[3 * (size_t)p + c] : 0.0;  // +0, not -0, where f = 0
		st = SM_OK;
		if (err != NULL) {
			err->status = SM_OK;
			err->message[0] = '\0';
		}
	}
	if (result != NULL)
		*result = res;
	work_free(&w);
	return st;
}

// Simulation: the functions CVODE calls. The right-hand side, the Jacobian evaluated and scattered
// into the dense solver's matrix or the KLU solver's CSR matrix (with the latter's pattern), CVODE's
// messages with their times on the simulation's axis, and the wrapper that times a matrix-based
// linear solver's set-up and solves. Creating a simulation and choosing its linear solver:
// simulation_create.c; advancing it: simulation.c.
//
// State, right-hand side and Jacobian:
//   y = [x; v; e; w] over the free particles, x' = v, v' = M^-1 f(x, v, t), e' = P_dissipated(x, v),
//   w' = P_input(x, v, t) - the driven particles' m a . v (sm_simulation_driving_power_at).
//   The Newton matrix of BDF is I - gamma J with
//     J = [[0, I, 0, 0], [M^-1 K, M^-1 D, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]],  K = df/dx, D = df/dv;
//   the energies e and w feed back into nothing, so their rows and columns of J are left out
//   (zero): Newton's iteration still converges, and they are integrated to the same tolerance.
// Linear solvers: dense LU of the full system (SUNDenseMatrix), sparse LU (KLU) of the full
// system in CSR form, and the reduced second-order solver of linear_solver_reduced.c.
#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_linearsolver.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// CVODE callbacks
// ---------------------------------------------------------------------------------------------

// Power the inputs deliver [W], from the velocities v and forces f of all particles (external
// forces included) and the external forces at one time. An external force on a free particle
// does f_ext . v. A driven particle follows its path because whatever drives it adds to the model's
// forces (f - f_ext: springs, damping, gravity, its load) what its acceleration a needs,
// m a - (f - f_ext); with the external force it takes, the outside does (m a - f + f_ext) . v on
// it. With the dissipated power they balance the change of kinetic, elastic and gravitational energy.
//
// CVODE integrates this power without the part m a . v, which is the rate of the driven particles'
// kinetic energy along their paths (sm_simulation_input_work adds that energy as the paths have it):
// a drive given a new acceleration along its velocity makes m a . v jump, and the rest of the power
// stays continuous, so CVODE's history can step over the change. with_kinetic_rate: the whole
// power; without it, the part CVODE integrates.
static double input_power(const sm_simulation* sim, const double* v, const double* f, const double* external,
                          bool with_kinetic_rate)
{
	double power = 0.0;
	if (sim->forced_particles > 0)
		for (int32_t k = 0; k < sim->free_count; k++) {
			const size_t p = 3 * (size_t)sim->free_particles[k];
			power += external[p] * v[p] + external[p + 1] * v[p + 1] + external[p + 2] * v[p + 2];
		}
	if (sim->driven_count > 0)
		for (int32_t k = 0; k < sim->constrained_count; k++) {
			const int32_t i = sim->constrained[k];
			if (sim->model->motion[i] != SM_PARTICLE_DRIVEN)
				continue;
			const size_t p = 3 * (size_t)i;
			const double m = with_kinetic_rate ? sim->model->mass[i] : 0.0;
			for (int c = 0; c < 3; c++)
				power += (m * sim->drive_acceleration[p + c] - f[p + c] + external[p + c]) * v[p + c];
		}
	return power;
}

double sm_simulation_input_power_at(const sm_simulation* sim, const double* v, const double* f,
                                    const double* external)
{
	return input_power(sim, v, f, external, true);
}

double sm_simulation_driving_power_at(const sm_simulation* sim, const double* v, const double* f,
                                      const double* external)
{
	return input_power(sim, v, f, external, false);
}

// The driven particles' kinetic energy [J] at the velocities v of all particles.
double sm_simulation_driven_kinetic_energy(const sm_simulation* sim, const double* v)
{
	double energy = 0.0;
	if (sim->driven_count > 0)
		for (int32_t k = 0; k < sim->constrained_count; k++) {
			const int32_t i = sim->constrained[k];
			if (sim->model->motion[i] == SM_PARTICLE_DRIVEN)
				energy += 0.5 * sim->model->mass[i] *
				          (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
		}
	return energy;
}

// y' = [v; M^-1 f; P_dissipated; P_input - m a . v]. A non-finite state, the energies included, is a
// recoverable failure (> 0): CVODE retries with a smaller step.
int sm_simulation_rhs(sunrealtype t, N_Vector yv, N_Vector ydotv, void* user_data)
{
	sm_simulation* sim = user_data;
	const double* y = N_VGetArrayPointer(yv);
	double* ydot = N_VGetArrayPointer(ydotv);
	const int64_t nd = sim->dofs;
	const int64_t length = sm_simulation_state_length(sim);
	for (int64_t i = 0; i < length; i++)
		if (!isfinite(y[i]))
			return 1;
	double* x = sim->work_position;
	double* v = sim->work_velocity;
	double* f = sim->work_force;
	sm_simulation_unpack(sim, t, y, x, v);
	const double start = sm_simulation_clock();
	const double* external = sm_simulation_external_forces(sim, t);
	double power;
	if (sm_simulation_has_reduced_solver(sim) && sm_reduced_rhs_wants_records(sim->linear_solver, t)) {
		power = sm_reduced_rhs_forces(sim->linear_solver, t, y, x, v, external, f);
		sim->base.jacobian_seconds += sm_simulation_clock() - start;
	} else {
		power = sm_model_forces_and_power(sim->model, x, v, external, f);
		sim->base.force_seconds += sm_simulation_clock() - start;
	}
	sim->rhs_evaluations++;
	memcpy(ydot, y + nd, (size_t)nd * sizeof(double));
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t p = 3 * (size_t)sim->free_particles[k];
		const size_t q = 3 * (size_t)k;
		const double w = sim->inverse_mass[k];
		ydot[nd + q] = f[p] * w;
		ydot[nd + q + 1] = f[p + 1] * w;
		ydot[nd + q + 2] = f[p + 2] * w;
	}
	ydot[sm_simulation_dissipated_index(sim)] = power;
	ydot[sm_simulation_work_index(sim)] = sm_simulation_driving_power_at(sim, v, f, external);
	for (int64_t i = nd; i < length; i++)
		if (!isfinite(ydot[i]))
			return 1;
	return 0;
}

int sm_simulation_fill_jacobian(sm_simulation* sim, double t, const double* y, sm_jacobian_variant variant)
{
	double* x = sim->work_position;
	double* v = sim->work_velocity;
	sm_simulation_unpack(sim, t, y, x, v);
	const double start = sm_simulation_clock();
	// The fused pass of forces and Jacobian blocks into the simulation's records (its forces, not
	// needed here, into the right-hand side's work array), then the assembly from them: what
	// sm_sparse_jacobian_fill does, without allocating its scratch at every evaluation.
	sm_status st = sm_model_forces_and_jacobians(sim->model, x, v, NULL, variant, sim->work_force,
	                                             sim->jacobian_records);
	if (st == SM_OK)
		st = sm_sparse_jacobian_fill_from_springs(sim->pattern, sim->model, sim->jacobian_records, sim->dfdx,
		                                          sim->dfdv);
	sim->base.jacobian_seconds += sm_simulation_clock() - start;
	sim->jacobian_evaluations++;
	sim->jacobian_out_of_memory = st == SM_ERROR_OUT_OF_MEMORY;
	return st == SM_OK ? 0 : -1;
}

// Dense J: [[0, I, 0, 0], [M^-1 K, M^-1 D, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]], scattered from
// the sparse fill.
int sm_simulation_jacobian_dense(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
                                 N_Vector tmp1, N_Vector tmp2, N_Vector tmp3)
{
	(void)fy, (void)tmp1, (void)tmp2, (void)tmp3;
	sm_simulation* sim = user_data;
	if (sm_simulation_fill_jacobian(sim, t, N_VGetArrayPointer(yv), sim->def.jacobian) != 0)
		return -1;
	const double start = sm_simulation_clock();
	const int64_t nd = sim->dofs;
	SUNMatZero(J);
	for (int64_t i = 0; i < nd; i++)
		SM_ELEMENT_D(J, i, nd + i) = 1.0;
	const int64_t* rows = sm_sparse_jacobian_row_pointers(sim->pattern);
	const int64_t* cols = sm_sparse_jacobian_column_indices(sim->pattern);
	for (int64_t i = 0; i < nd; i++) {
		const double w = 1.0 / sim->mass_dof[i];
		for (int64_t e = rows[i]; e < rows[i + 1]; e++) {
			SM_ELEMENT_D(J, nd + i, cols[e]) = w * sim->dfdx[e];
			SM_ELEMENT_D(J, nd + i, nd + cols[e]) = w * sim->dfdv[e];
		}
	}
	sim->base.jacobian_seconds += sm_simulation_clock() - start;
	return 0;
}

// Pattern of the (6nf + 2) CSR matrix for KLU, every diagonal entry present (CVODE adds the
// identity in place): x row i: (i, i) = 0 and (i, nd + i) = 1; v row i: the pattern row of K
// then the same columns shifted by nd for D; the energies' rows: their diagonal entries, 0.
sm_status sm_simulation_build_klu_pattern(sm_simulation* sim)
{
	const int64_t nd = sim->dofs;
	const int64_t nnz = sm_sparse_jacobian_nonzeros(sim->pattern);
	const int64_t* rows = sm_sparse_jacobian_row_pointers(sim->pattern);
	const int64_t* cols = sm_sparse_jacobian_column_indices(sim->pattern);
	sim->klu_row_pointers = malloc((size_t)(2 * nd + SM_ENERGY_COMPONENTS + 1) * sizeof(int64_t));
	sim->klu_column_indices = malloc((size_t)(2 * nd + 2 * nnz + SM_ENERGY_COMPONENTS) * sizeof(int64_t));
	if (!sim->klu_row_pointers || !sim->klu_column_indices)
		return SM_ERROR_OUT_OF_MEMORY;
	int64_t e = 0;
	for (int64_t i = 0; i < nd; i++) {
		sim->klu_row_pointers[i] = e;
		sim->klu_column_indices[e++] = i;
		sim->klu_column_indices[e++] = nd + i;
	}
	for (int64_t i = 0; i < nd; i++) {
		sim->klu_row_pointers[nd + i] = e;
		for (int64_t k = rows[i]; k < rows[i + 1]; k++)
			sim->klu_column_indices[e++] = cols[k];
		for (int64_t k = rows[i]; k < rows[i + 1]; k++)
			sim->klu_column_indices[e++] = nd + cols[k];
	}
	for (int64_t i = 2 * nd; i < 2 * nd + SM_ENERGY_COMPONENTS; i++) {
		sim->klu_row_pointers[i] = e;
		sim->klu_column_indices[e++] = i;
	}
	sim->klu_row_pointers[2 * nd + SM_ENERGY_COMPONENTS] = e;
	return SM_OK;
}

int sm_simulation_jacobian_sparse(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
                                  N_Vector tmp1, N_Vector tmp2, N_Vector tmp3)
{
	(void)fy, (void)tmp1, (void)tmp2, (void)tmp3;
	sm_simulation* sim = user_data;
	if (sm_simulation_fill_jacobian(sim, t, N_VGetArrayPointer(yv), sim->def.jacobian) != 0)
		return -1;
	const double start = sm_simulation_clock();
	const int64_t nd = sim->dofs;
	const int64_t* rows = sm_sparse_jacobian_row_pointers(sim->pattern);
	const int64_t total = sim->klu_row_pointers[2 * nd + SM_ENERGY_COMPONENTS];
	if (SUNSparseMatrix_NNZ(J) < total && SUNSparseMatrix_Reallocate(J, total) != 0)
		return -1;
	// CVODE zeroes the matrix, index arrays included, before each call: restore the pattern.
	memcpy(SUNSparseMatrix_IndexPointers(J), sim->klu_row_pointers,
	       (size_t)(2 * nd + SM_ENERGY_COMPONENTS + 1) * sizeof(int64_t));
	memcpy(SUNSparseMatrix_IndexValues(J), sim->klu_column_indices, (size_t)total * sizeof(int64_t));
	double* val = SUNSparseMatrix_Data(J);
	int64_t e = 0;
	for (int64_t i = 0; i < nd; i++) {
		val[e++] = 0.0;
		val[e++] = 1.0;
	}
	for (int64_t i = 0; i < nd; i++) {
		const double w = 1.0 / sim->mass_dof[i];
		const int64_t len = rows[i + 1] - rows[i];
		const double* kx = sim->dfdx + rows[i];
		const double* kv = sim->dfdv + rows[i];
		for (int64_t k = 0; k < len; k++)
			val[e + k] = w * kx[k];
		e += len;
		for (int64_t k = 0; k < len; k++)
			val[e + k] = w * kv[k];
		e += len;
	}
	for (int c = 0; c < SM_ENERGY_COMPONENTS; c++)
		val[e + c] = 0.0;
	sim->base.jacobian_seconds += sm_simulation_clock() - start;
	return 0;
}

// CVODE's messages give times on its own axis, which starts at 0 at its last (re)initialisation
// (set_state, a break, a changed input, a failure): a failure right after a restart at 0.5 s
// said "At t = 0". Each time named so ("t = ", and "tout", "tstop", "tcur", "tcur - hu", "t0") is
// rewritten on the simulation's axis, origin + t, in as many digits as CVODE gave (6 with SUNDIALS
// 6, 15 with 7) beyond those the origin adds: at a restart at 0.3 s, "t = 0.0214454" reads
// "t = 0.3214454".
static const char* const cvode_time_names[] = {
    "t = ", "tout = ", "tstop = ", "tcur - hu = ", "tcur = ", "t0 = "};

// The length of the time's name that starts a word at p in msg, or 0 if none does.
static size_t time_name_at(const char* msg, const char* p)
{
	if (p > msg && (isalnum((unsigned char)p[-1]) || p[-1] == '_'))
		return 0;
	for (size_t k = 0; k < sizeof cvode_time_names / sizeof cvode_time_names[0]; k++) {
		const size_t length = strlen(cvode_time_names[k]);
		if (strncmp(p, cvode_time_names[k], length) == 0)
			return length;
	}
	return 0;
}

static void on_simulation_axis(const char* msg, double origin, char* out, size_t size)
{
	size_t n = 0;
	for (const char* p = msg; *p != '\0' && n + 1 < size;) {
		const size_t name = time_name_at(msg, p);
		char* end = NULL;
		const double t = name > 0 ? strtod(p + name, &end) : 0.0;
		if (name == 0 || end == p + name || !isfinite(t)) {
			out[n++] = *p++;
			continue;
		}
		const double time = origin + t;
		char text[SM_NUMBER_TEXT_CAPACITY];
		if (t == 0.0 || time == 0.0 || !isfinite(time)) {
			sm_format_number(time, text);
		} else {
			// CVODE's digits and those the origin adds, up to the 17 that tell any two doubles apart.
			const int extra = (int)floor(log10(fabs(time))) - (int)floor(log10(fabs(t)));
			const int digits = SM_CVODE_MESSAGE_DIGITS + (extra > 0 ? extra : 0);
			sm_format_c_locale(text, sizeof text, "%.*g", digits < 17 ? digits : 17, time);
		}
		const int written = snprintf(out + n, size - n, "%.*s%s", (int)name, p, text);
		if (written > 0)
			n = n + (size_t)written < size ? n + (size_t)written : size - 1;
		p = end;
	}
	out[n] = '\0';
}

static void record_solver_message(sm_simulation* sim, const char* function, const char* msg)
{
	const int prefix = snprintf(sim->solver_message, sizeof sim->solver_message, "%s: ", function);
	if (prefix >= 0 && (size_t)prefix < sizeof sim->solver_message - 1)
		on_simulation_axis(msg, sim->time_origin, sim->solver_message + prefix,
		                   sizeof sim->solver_message - (size_t)prefix);
}

#if SUNDIALS_VERSION_MAJOR >= 7
void sm_simulation_error_handler(int line, const char* function, const char* file, const char* msg,
                                 SUNErrCode code, void* user_data, SUNContext context)
{
	(void)line, (void)file, (void)context;
	// SUNDIALS 7 names the function an error arose in, 6 the one called: a failed step of CVode,
	// which 6 reported as CVode's, 7 reports from cvHandleFailure. A module's error without a
	// message of its own has the text of its code.
	record_solver_message(user_data, strcmp(function, "cvHandleFailure") == 0 ? "CVode" : function,
	                      msg ? msg : SUNGetErrMsg(code));
}
#else
void sm_simulation_error_handler(int error_code, const char* module, const char* function, char* msg,
                                 void* user_data)
{
	(void)error_code, (void)module;
	record_solver_message(user_data, function, msg);
}
#endif

// ---------------------------------------------------------------------------------------------
// Timed wrapper around a matrix-based linear solver (dense LU, KLU)
// ---------------------------------------------------------------------------------------------

typedef struct timed_content {
	sm_simulation* sim;
	SUNLinearSolver inner;
} timed_content;

static SUNLinearSolver_Type timed_type(SUNLinearSolver ls)
{
	return SUNLinSolGetType(((timed_content*)ls->content)->inner);
}

static SUNLinearSolver_ID timed_id(SUNLinearSolver ls)
{
	return SUNLinSolGetID(((timed_content*)ls->content)->inner);
}

static int timed_initialize(SUNLinearSolver ls)
{
	return SUNLinSolInitialize(((timed_content*)ls->content)->inner);
}

static int timed_setup(SUNLinearSolver ls, SUNMatrix A)
{
	timed_content* c = ls->content;
	const double start = sm_simulation_clock();
	int r = SUNLinSolSetup(c->inner, A);
	c->sim->base.linear_solve_seconds += sm_simulation_clock() - start;
	c->sim->factorizations++;
	return r;
}

static int timed_solve(SUNLinearSolver ls, SUNMatrix A, N_Vector x, N_Vector b, sunrealtype tol)
{
	timed_content* c = ls->content;
	const double start = sm_simulation_clock();
	int r = SUNLinSolSolve(c->inner, A, x, b, tol);
	c->sim->base.linear_solve_seconds += sm_simulation_clock() - start;
	c->sim->linear_iterations++;
	return r;
}

static sunindextype timed_last_flag(SUNLinearSolver ls)
{
	return SUNLinSolLastFlag(((timed_content*)ls->content)->inner);
}

static int timed_free(SUNLinearSolver ls)
{
	if (ls == NULL)
		return 0;
	timed_content* c = ls->content;
	if (c != NULL) {
		SUNLinSolFree(c->inner);
		free(c);
		ls->content = NULL;
	}
	SUNLinSolFreeEmpty(ls);
	return 0;
}

SUNLinearSolver sm_timed_solver_create(sm_simulation* sim, SUNLinearSolver inner)
{
	if (inner == NULL)
		return NULL;
	SUNLinearSolver ls = SUNLinSolNewEmpty(sim->context);
	timed_content* c = malloc(sizeof *c);
	if (ls == NULL || c == NULL) {
		free(c);
		if (ls)
			SUNLinSolFreeEmpty(ls);
		SUNLinSolFree(inner);
		return NULL;
	}
	c->sim = sim;
	c->inner = inner;
	ls->content = c;
	ls->ops->gettype = timed_type;
	ls->ops->getid = timed_id;
	ls->ops->initialize = timed_initialize;
	ls->ops->setup = timed_setup;
	ls->ops->solve = timed_solve;
	ls->ops->lastflag = timed_last_flag;
	ls->ops->free = timed_free;
	return ls;
}

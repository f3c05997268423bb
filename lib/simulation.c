// Time integration of a model with SUNDIALS CVODE.
//
// State, right-hand side and Jacobian:
//   y = [x; v; e; w] over the free particles, x' = v, v' = M^-1 f(x, v, t), e' = P_dissipated(x, v),
//   w' = P_input(x, v, t) (input_power).
//   The Newton matrix of BDF is I - gamma J with
//     J = [[0, I, 0, 0], [M^-1 K, M^-1 D, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]],  K = df/dx, D = df/dv;
//   the energies e and w feed back into nothing, so their rows and columns of J are left out
//   (zero): Newton's iteration still converges, and they are integrated to the same tolerance.
// Linear solvers: dense LU of the full system (SUNDenseMatrix), sparse LU (KLU) of the full
// system in CSR form, and the reduced second-order solver of linear_solver_reduced.c.
// Breaking springs: simulation_events.c. State snapshots (save, restore, serialise):
// simulation_state.c.
#define _POSIX_C_SOURCE 200809L

#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <ctype.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

// Free degrees of freedom up to which SM_SOLVER_AUTO picks the dense solver; above, it picks
// the reduced conjugate-gradient solver. Measured with `springmass run` on ropes, small sheets,
// a block, a mesh and anchored sheets of 1 to 9 free particles (bench/README.md, "The linear
// solver auto picks"): SUNDIALS' dense LU (Debian's archives are built without optimisation)
// costs about what the reduced solver does with 1 or 2 free particles, 1.5 - 2.6 times as much
// from 3 to 5 and 3 - 5 times from 6 on. On the benchmark cloth from n = 8 to 64
// block-Jacobi conjugate gradients beat the CHOLMOD-preconditioned ones by 1.3 to 1.7 times and
// KLU on the full system by more.
#define AUTO_DENSE_MAX_DOFS 6

// Time resolution relative to max(1 s, |t|) [1]. CVODE's first step after a (re)start must
// exceed about 2 eps |t| (CV_TOO_CLOSE), and at t = 0 an interval of 1e-200 s made its initial
// step estimate underflow (CV_ILL_INPUT, "tstop behind current t"): sm_simulation_advance covers
// an interval below this with an explicit step of its own. The FMU's shortest communication
// step is the same.
#define TIME_RESOLUTION (4.0 * DBL_EPSILON)
// How far ahead a stop time or an end sizes CVODE's first step after a (re)initialisation [s]:
// 1e9 s, whose least first step, 100 eps of it, is 2.2e-5 s (simulation.h). An advance to a
// farther end steps one at a time (step_one_at_a_time), which caps it.
#define STOP_HORIZON 1e9

double sm_simulation_clock(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

sm_status sm_simulation_fail(sm_simulation* sim, sm_status status, const char* format, ...)
{
	va_list args;
	va_start(args, format);
	sm_vformat_c_locale(sim->last_error, sizeof sim->last_error, format, args);
	va_end(args);
	return status;
}

sm_simulation_def sm_default_simulation_def(void)
{
	sm_simulation_def def;
	memset(&def, 0, sizeof def);
	def.method = SM_METHOD_BDF;
	def.solver = SM_SOLVER_AUTO;
	def.jacobian = SM_JACOBIAN_EXACT;
	def.relative_tolerance = 1e-6;
	def.absolute_tolerance_position = 1e-8;
	def.absolute_tolerance_velocity = 1e-6;
	def.max_step = 0.0;
	def.max_steps = 100000;
	def.restart_on_input_change = true;
	def.threads = 1;
	return def;
}

static const char* const solver_names[SM_SOLVER_COUNT] = {"auto", "dense", "klu", "pcg", "cholmod"};

const char* sm_linear_solver_name(sm_linear_solver solver)
{
	if ((int)solver < 0 || solver >= SM_SOLVER_COUNT)
		return "unknown";
	return solver_names[solver];
}

const char* sm_method_name(sm_method method)
{
	switch (method) {
	case SM_METHOD_BDF: return "bdf";
	case SM_METHOD_ADAMS: return "adams";
	}
	return "unknown";
}

sm_status sm_method_from_name(const char* name, sm_method* method)
{
	if (name == NULL || method == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (strcmp(name, "bdf") == 0)
		*method = SM_METHOD_BDF;
	else if (strcmp(name, "adams") == 0)
		*method = SM_METHOD_ADAMS;
	else
		return SM_ERROR_INVALID_ARGUMENT;
	return SM_OK;
}

sm_status sm_linear_solver_from_name(const char* name, sm_linear_solver* solver)
{
	for (int i = 0; name != NULL && solver != NULL && i < SM_SOLVER_COUNT; i++)
		if (strcmp(name, solver_names[i]) == 0) {
			*solver = (sm_linear_solver)i;
			return SM_OK;
		}
	return SM_ERROR_INVALID_ARGUMENT;
}

// ---------------------------------------------------------------------------------------------
// State packing
// ---------------------------------------------------------------------------------------------

// Driven particle i's position x and, if v is not NULL, velocity v at CVODE time t. Its motion has
// run for s = (time_origin - drive_time) + t: both differences are of times near each other, so
// that neither loses the precision of a large time. Its position is x0 + s (v0 + s a / 2), its
// velocity v0 + s a.
static void driven_state(const sm_simulation* sim, int32_t i, double t, double x[3], double v[3])
{
	const size_t p = 3 * (size_t)i;
	const double s = (sim->time_origin - sim->drive_time[i]) + t;
	for (int c = 0; c < 3; c++) {
		const double a = sim->drive_acceleration[p + c];
		x[c] = sim->drive_position[p + c] + s * (sim->drive_velocity[p + c] + 0.5 * s * a);
		if (v != NULL)
			v[c] = sim->drive_velocity[p + c] + s * a;
	}
}

void sm_simulation_unpack(sm_simulation* sim, double t, const double* y, double* x, double* v)
{
	const int64_t nd = sim->dofs;
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t p = 3 * (size_t)sim->free_particles[k];
		const size_t q = 3 * (size_t)k;
		x[p] = y[q];
		x[p + 1] = y[q + 1];
		x[p + 2] = y[q + 2];
		v[p] = y[nd + q];
		v[p + 1] = y[nd + q + 1];
		v[p + 2] = y[nd + q + 2];
	}
	const sm_model* m = sim->model;
	for (int32_t k = 0; k < sim->constrained_count; k++) {
		const int32_t i = sim->constrained[k];
		const size_t p = 3 * (size_t)i;
		if (m->motion[i] == SM_PARTICLE_DRIVEN) {
			driven_state(sim, i, t, x + p, v + p);
		} else {
			for (int c = 0; c < 3; c++) {
				x[p + c] = m->position[p + c];
				v[p + c] = 0.0;
			}
		}
	}
}

// A ramp's time since it was set is a difference of times near each other, as a driven motion's.
const double* sm_simulation_external_forces(sm_simulation* sim, double t)
{
	if (sim->ramping_forces == 0)
		return sim->external_force;
	for (int32_t i = 0; i < sim->particle_count; i++) {
		const size_t p = 3 * (size_t)i;
		const double dt = (sim->time_origin - sim->force_time[i]) + t;
		for (int c = 0; c < 3; c++)
			sim->work_external[p + c] = sim->external_force[p + c] + sim->force_rate[p + c] * dt;
	}
	return sim->work_external;
}

// Writes the free particles' entries of x and v into y (the energies e and w untouched).
static void pack(const sm_simulation* sim, const double* x, const double* v, double* y)
{
	const int64_t nd = sim->dofs;
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t p = 3 * (size_t)sim->free_particles[k];
		const size_t q = 3 * (size_t)k;
		for (int c = 0; c < 3; c++) {
			y[q + c] = x[p + c];
			y[nd + q + c] = v[p + c];
		}
	}
}

void sm_simulation_refresh_outputs(sm_simulation* sim)
{
	sm_simulation_unpack(sim, sm_simulation_cvode_time(sim, sim->time), N_VGetArrayPointer(sim->y),
	                     sim->position, sim->velocity);
}

// ---------------------------------------------------------------------------------------------
// CVODE callbacks
// ---------------------------------------------------------------------------------------------

// Whether the linear solver is the reduced one (linear_solver_reduced.c). Adams' fixed-point
// iteration has none, whatever the options name.
static bool has_reduced_solver(const sm_simulation* sim)
{
	return sim->linear_solver != NULL &&
	       (sim->solver == SM_SOLVER_REDUCED_PCG || sim->solver == SM_SOLVER_REDUCED_CHOLMOD);
}

// Power the inputs deliver [W], from the velocities v and forces f of all particles (external
// forces included) and the external forces at one time. An external force on a free particle
// does f_ext . v. A driven particle follows its path because whatever drives it adds to the model's
// forces (f - f_ext: springs, damping, gravity, its load) what its acceleration a needs,
// m a - (f - f_ext); with the external force it takes, the outside does (m a - f + f_ext) . v on
// it. With the dissipated power they balance the change of kinetic, elastic and gravitational energy.
static double input_power(const sm_simulation* sim, const double* v, const double* f, const double* external)
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
			const double m = sim->model->mass[i];
			for (int c = 0; c < 3; c++)
				power += (m * sim->drive_acceleration[p + c] - f[p + c] + external[p + c]) * v[p + c];
		}
	return power;
}

// y' = [v; M^-1 f; P_dissipated; P_input]. A non-finite state, the energies included, is a
// recoverable failure (> 0): CVODE retries with a smaller step.
static int rhs(sunrealtype t, N_Vector yv, N_Vector ydotv, void* user_data)
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
	if (has_reduced_solver(sim) && sm_reduced_rhs_wants_records(sim->linear_solver, t)) {
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
	ydot[sm_simulation_work_index(sim)] = input_power(sim, v, f, external);
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
static int jacobian_dense(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
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
static sm_status build_klu_pattern(sm_simulation* sim)
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

static int jacobian_sparse(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
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
// rewritten on the simulation's axis, origin + t, in as many digits as CVODE gave (6) beyond
// those the origin adds: at a restart at 0.3 s, "t = 0.0214454" reads "t = 0.3214454".
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
			const int extra = (int)floor(log10(fabs(time))) - (int)floor(log10(fabs(t)));
			sm_format_c_locale(text, sizeof text, "%.*g", 6 + (extra > 0 ? (extra < 11 ? extra : 11) : 0),
			                   time);
		}
		const int written = snprintf(out + n, size - n, "%.*s%s", (int)name, p, text);
		if (written > 0)
			n = n + (size_t)written < size ? n + (size_t)written : size - 1;
		p = end;
	}
	out[n] = '\0';
}

static void error_handler(int error_code, const char* module, const char* function, char* msg,
                          void* user_data)
{
	(void)error_code, (void)module;
	sm_simulation* sim = user_data;
	const int prefix = snprintf(sim->solver_message, sizeof sim->solver_message, "%s: ", function);
	if (prefix >= 0 && (size_t)prefix < sizeof sim->solver_message - 1)
		on_simulation_axis(msg, sim->time_origin, sim->solver_message + prefix,
		                   sizeof sim->solver_message - (size_t)prefix);
}

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

// ---------------------------------------------------------------------------------------------
// Creation
// ---------------------------------------------------------------------------------------------

static sm_status check_def(const sm_simulation_def* def, sm_error* err)
{
	if ((int)def->method < 0 || def->method > SM_METHOD_ADAMS)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown method %d",
		                    (int)def->method);
	if ((int)def->solver < 0 || def->solver >= SM_SOLVER_COUNT)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown linear solver %d",
		                    (int)def->solver);
	if ((int)def->jacobian < 0 || def->jacobian > SM_JACOBIAN_DEFINITE)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown Jacobian variant %d",
		                    (int)def->jacobian);
	const struct {
		const char* name;
		double value;
	} positive[] = {{"relative_tolerance", def->relative_tolerance},
	                {"absolute_tolerance_position", def->absolute_tolerance_position},
	                {"absolute_tolerance_velocity", def->absolute_tolerance_velocity}};
	for (size_t i = 0; i < sizeof positive / sizeof positive[0]; i++)
		if (!(isfinite(positive[i].value) && positive[i].value > 0.0))
			return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: %s = %g must be finite and > 0",
			                    positive[i].name, positive[i].value);
	// Below SM_MIN_ABSOLUTE_TOLERANCE CVODE's error norm overflows (simulation.h).
	// Both numbers in the digits that read back: 9.9999999999e-151 is not 1e-150.
	const bool position_ok = def->absolute_tolerance_position >= SM_MIN_ABSOLUTE_TOLERANCE;
	if (!position_ok || !(def->absolute_tolerance_velocity >= SM_MIN_ABSOLUTE_TOLERANCE)) {
		char value[SM_NUMBER_TEXT_CAPACITY], floor[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(position_ok ? def->absolute_tolerance_velocity : def->absolute_tolerance_position,
		                 value);
		sm_format_number(SM_MIN_ABSOLUTE_TOLERANCE, floor);
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: absolute_tolerance_%s = %s must be at least %s: CVODE's error norm "
		                    "sums (error / atol)^2, which overflows for smaller tolerances",
		                    position_ok ? "velocity" : "position", value, floor);
	}
	if (!(def->relative_tolerance < 1.0))
		return sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "simulation: relative_tolerance = %g must be < 1 (a relative error of 100 %% or more)",
		    def->relative_tolerance);
	// Below the machine epsilon CVODE cannot meet it (SM_MIN_RELATIVE_TOLERANCE, simulation.h).
	// Both in their shortest exact digits: a value an ulp below the floor reads as below it.
	if (!(def->relative_tolerance >= SM_MIN_RELATIVE_TOLERANCE)) {
		char value[SM_NUMBER_TEXT_CAPACITY], floor[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(def->relative_tolerance, value);
		sm_format_number(SM_MIN_RELATIVE_TOLERANCE, floor);
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: relative_tolerance = %s must be at least %s, the machine epsilon: "
		                    "CVODE cannot hold errors below the rounding of the state",
		                    value, floor);
	}
	if (!(isfinite(def->max_step) && def->max_step >= 0.0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: max_step = %g must be finite and >= 0", def->max_step);
	if (def->max_step > 0.0 && def->max_step <= SM_MAX_STEP_FLOOR)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: max_step = %g s is too small for CVODE, whose 1 / max_step would be "
		                    "beyond the largest double; give 0 for no limit or a step above %g s",
		                    def->max_step, SM_MAX_STEP_FLOOR);
	if (def->max_steps <= 0)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: max_steps = %d must be > 0",
		                    (int)def->max_steps);
	if (def->threads < 1)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: threads = %d must be >= 1",
		                    (int)def->threads);
	return SM_OK;
}

static sm_linear_solver resolve_solver(const sm_simulation_def* def, int64_t dofs)
{
	if (def->solver != SM_SOLVER_AUTO)
		return def->solver;
	if (dofs <= AUTO_DENSE_MAX_DOFS)
		return SM_SOLVER_DENSE;
	return SM_SOLVER_REDUCED_PCG;
}

// Masses of the free particles, from the simulation's model.
static void refresh_masses(sm_simulation* sim)
{
	for (int32_t k = 0; k < sim->free_count; k++) {
		const double m = sim->model->mass[sim->free_particles[k]];
		sim->inverse_mass[k] = 1.0 / m;
		sim->mass_dof[3 * k] = sim->mass_dof[3 * k + 1] = sim->mass_dof[3 * k + 2] = m;
	}
}

// The springs at each driven particle (driven_spring_start, driven_springs): counted, then listed.
static sm_status build_driven_springs(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	int32_t* start = calloc((size_t)m->particle_count + 2, sizeof(int32_t));
	if (start == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t ends[2] = {m->spring_a[s], m->spring_b[s]};
		for (int e = 0; e < 2; e++)
			start[ends[e] + 2] += m->motion[ends[e]] == SM_PARTICLE_DRIVEN;
	}
	for (int32_t i = 0; i < m->particle_count; i++)
		start[i + 2] += start[i + 1];
	int32_t* springs = malloc(((size_t)start[m->particle_count + 1] + 1) * sizeof(int32_t));
	if (springs == NULL) {
		free(start);
		return SM_ERROR_OUT_OF_MEMORY;
	}
	// start[i + 1] is the next place of particle i's springs, and ends as the end of them.
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t ends[2] = {m->spring_a[s], m->spring_b[s]};
		for (int e = 0; e < 2; e++)
			if (m->motion[ends[e]] == SM_PARTICLE_DRIVEN)
				springs[start[ends[e] + 1]++] = s;
	}
	sim->driven_spring_start = start;
	sim->driven_springs = springs;
	return SM_OK;
}

// Everything from the model's stored initial state: positions, velocities, driven motion,
// no external forces, e = w = 0.
static void load_initial_state(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	const size_t n3 = 3 * (size_t)sim->particle_count;
	if (n3 > 0) {  // a model without particles has no arrays to copy from
		memcpy(sim->drive_position, m->position, n3 * sizeof(double));
		memcpy(sim->drive_velocity, m->velocity, n3 * sizeof(double));
	}
	for (int32_t i = 0; i < sim->particle_count; i++)
		sim->drive_time[i] = sim->force_time[i] = 0.0;
	memset(sim->drive_acceleration, 0, n3 * sizeof(double));
	memset(sim->external_force, 0, n3 * sizeof(double));
	memset(sim->force_rate, 0, n3 * sizeof(double));
	sim->ramping_forces = 0;
	sim->forced_particles = 0;
	double* y = N_VGetArrayPointer(sim->y);
	pack(sim, m->position, m->velocity, y);
	y[sm_simulation_dissipated_index(sim)] = 0.0;
	y[sm_simulation_work_index(sim)] = 0.0;
	sim->jump_work = 0.0;
	sim->time = 0.0;
	sim->time_origin = 0.0;
	sm_simulation_refresh_outputs(sim);
}

static sm_status attach_linear_solver(sm_simulation* sim)
{
	if (sim->def.method == SM_METHOD_ADAMS) {
		SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(sim->y, 0, sim->context);
		if (!nls)
			return SM_ERROR_OUT_OF_MEMORY;
		// CVODE does not take ownership of the nonlinear solver: the simulation frees it.
		int flag = CVodeSetNonlinearSolver(sim->cvode, nls);
		if (flag != CV_SUCCESS) {
			SUNNonlinSolFree(nls);
			return SM_ERROR_SOLVER;
		}
		sim->fixed_point = nls;
		return SM_OK;
	}
	const int64_t n = sm_simulation_state_length(sim);
	switch (sim->solver) {
	case SM_SOLVER_DENSE: {
		sim->matrix = SUNDenseMatrix(n, n, sim->context);
		if (!sim->matrix)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->linear_solver = sm_timed_solver_create(sim, SUNLinSol_Dense(sim->y, sim->matrix, sim->context));
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, sim->matrix) != CVLS_SUCCESS ||
		    CVodeSetJacFn(sim->cvode, jacobian_dense) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_KLU: {
		if (build_klu_pattern(sim) != SM_OK)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->matrix = SUNSparseMatrix(n, n, sim->klu_row_pointers[n], CSR_MAT, sim->context);
		if (!sim->matrix)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->linear_solver = sm_timed_solver_create(sim, SUNLinSol_KLU(sim->y, sim->matrix, sim->context));
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, sim->matrix) != CVLS_SUCCESS ||
		    CVodeSetJacFn(sim->cvode, jacobian_sparse) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_REDUCED_PCG:
	case SM_SOLVER_REDUCED_CHOLMOD: {
		sim->linear_solver = sm_reduced_solver_create(sim, sim->solver == SM_SOLVER_REDUCED_CHOLMOD);
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, NULL) != CVLS_SUCCESS ||
		    CVodeSetPreconditioner(sim->cvode, sm_reduced_pset, sm_reduced_psolve) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_AUTO:
	case SM_SOLVER_COUNT: break;
	}
	return SM_ERROR_INVALID_ARGUMENT;
}

// CVODE's error weights w_i = 1 / (rtol |y_i| + atol_i), computed as CVodeSVtolerances' own
// function computes them (the same bits), from the simulation's absolute tolerances. Given to
// CVodeWFtolerances because CVodeSVtolerances clones the tolerance vector and SUNDIALS 6.4.1 then
// writes into the clone without checking that it was made: out of memory, that crashes.
static int error_weights(N_Vector yv, N_Vector wv, void* user_data)
{
	const sm_simulation* sim = user_data;
	const double* y = N_VGetArrayPointer(yv);
	const double* atol = N_VGetArrayPointer(sim->tolerances);
	double* w = N_VGetArrayPointer(wv);
	const double rtol = sim->def.relative_tolerance;
	const sunindextype n = N_VGetLength(yv);
	for (sunindextype i = 0; i < n; i++) {
		const double t = rtol * fabs(y[i]) + atol[i];
		if (t <= 0.0)
			return -1;  // as CVODE: a zero or negative weight is an error
		w[i] = 1.0 / t;
	}
	return 0;
}

static sm_status setup_cvode(sm_simulation* sim)
{
	const int64_t nd = sim->dofs;
	double* tol = N_VGetArrayPointer(sim->tolerances);
	for (int64_t i = 0; i < nd; i++) {
		tol[i] = sim->def.absolute_tolerance_position;
		tol[nd + i] = sim->def.absolute_tolerance_velocity;
	}
	// The energies [J] share the velocities' absolute tolerance.
	tol[sm_simulation_dissipated_index(sim)] = sim->def.absolute_tolerance_velocity;
	tol[sm_simulation_work_index(sim)] = sim->def.absolute_tolerance_velocity;
	sim->cvode = CVodeCreate(sim->def.method == SM_METHOD_ADAMS ? CV_ADAMS : CV_BDF, sim->context);
	if (!sim->cvode)
		return SM_ERROR_OUT_OF_MEMORY;
	if (CVodeSetErrHandlerFn(sim->cvode, error_handler, sim) != CV_SUCCESS ||
	    CVodeInit(sim->cvode, rhs, sm_simulation_cvode_time(sim, sim->time), sim->y) != CV_SUCCESS ||
	    CVodeWFtolerances(sim->cvode, error_weights) != CV_SUCCESS ||
	    CVodeSetUserData(sim->cvode, sim) != CV_SUCCESS ||
	    CVodeSetMaxNumSteps(sim->cvode, sim->def.max_steps) != CV_SUCCESS ||
	    CVodeSetMaxStep(sim->cvode, sim->def.max_step) != CV_SUCCESS)
		return SM_ERROR_SOLVER;
	// CVODE's warnings that t + h rounds to t are not printed (its time axis starts at every
	// (re)initialisation, so they would come only after a long run without one).
	CVodeSetMaxHnilWarns(sim->cvode, -1);
	sm_status st = sm_simulation_build_events(sim);
	if (st != SM_OK)
		return st;
	return attach_linear_solver(sim);
}

sm_simulation* sm_simulation_create(const sm_model* model, const sm_simulation_def* def, sm_error* err)
{
	sm_error_clear(err);
	if (model == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: model is NULL");
		return NULL;
	}
	sm_simulation_def d = def ? *def : sm_default_simulation_def();
	if (check_def(&d, err) != SM_OK)
		return NULL;
	sm_simulation* sim = calloc(1, sizeof *sim);
	if (!sim) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "simulation: out of memory");
		return NULL;
	}
	sim->def = d;
	sim->model = sm_model_clone(model);
	if (!sim->model)
		goto out_of_memory;
	const sm_model* m = sim->model;
	const int32_t n = m->particle_count;
	sim->particle_count = n;
	sim->spring_count = m->spring_count;
	sim->free_count = m->free_count;
	sim->dofs = 3 * (int64_t)m->free_count;
	sim->constrained_count = n - m->free_count;
	sim->solver = resolve_solver(&d, sim->dofs);
	const size_t n3 = 3 * (size_t)n + 1;
	sim->initial_enabled = malloc((size_t)m->spring_count + 1);
	sim->free_particles = malloc(((size_t)sim->free_count + 1) * sizeof(int32_t));
	sim->constrained = malloc(((size_t)sim->constrained_count + 1) * sizeof(int32_t));
	sim->inverse_mass = malloc(((size_t)sim->free_count + 1) * sizeof(double));
	sim->mass_dof = malloc(((size_t)sim->dofs + 1) * sizeof(double));
	sim->origin_slot = malloc(((size_t)n + 1) * sizeof(int32_t));
	double** arrays[] = {&sim->position,       &sim->velocity,           &sim->external_force,
	                     &sim->force_rate,     &sim->force_time,         &sim->drive_position,
	                     &sim->drive_velocity, &sim->drive_acceleration, &sim->drive_time,
	                     &sim->work_position,  &sim->work_velocity,      &sim->work_force,
	                     &sim->work_external};
	for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
		if (!(*arrays[i] = calloc(n3, sizeof(double))))
			goto out_of_memory;
	if (!sim->initial_enabled || !sim->free_particles || !sim->constrained || !sim->inverse_mass ||
	    !sim->mass_dof || !sim->origin_slot)
		goto out_of_memory;
	for (int32_t i = 0; i < n; i++)
		sim->origin_slot[i] = -1;
	if (m->spring_count > 0)  // no array to copy from in a model without springs
		memcpy(sim->initial_enabled, m->enabled, (size_t)m->spring_count);
	for (int32_t i = 0, kf = 0, kc = 0; i < n; i++) {
		if (m->motion[i] == SM_PARTICLE_FREE)
			sim->free_particles[kf++] = i;
		else
			sim->constrained[kc++] = i;
		sim->driven_count += m->motion[i] == SM_PARTICLE_DRIVEN;
	}
	refresh_masses(sim);
	if (build_driven_springs(sim) != SM_OK)
		goto out_of_memory;
	// The assembled sparse Jacobian (conjugate gradients use the springs' factored blocks only).
	if (sim->solver == SM_SOLVER_DENSE || sim->solver == SM_SOLVER_KLU ||
	    sim->solver == SM_SOLVER_REDUCED_CHOLMOD) {
		sim->pattern = sm_sparse_jacobian_create(m);
		if (!sim->pattern)
			goto out_of_memory;
		const size_t nnz = (size_t)sm_sparse_jacobian_nonzeros(sim->pattern) + 1;
		sim->dfdx = malloc(nnz * sizeof(double));
		sim->dfdv = malloc(nnz * sizeof(double));
		if (!sim->dfdx || !sim->dfdv)
			goto out_of_memory;
	}
	if (sim->solver == SM_SOLVER_DENSE || sim->solver == SM_SOLVER_KLU) {
		sim->jacobian_records = sm_spring_jacobians_create(m);
		if (!sim->jacobian_records)
			goto out_of_memory;
	}
	if (SUNContext_Create(NULL, &sim->context) != 0) {
		sim->context = NULL;
		goto out_of_memory;
	}
	sim->y = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	sim->y_saved = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	sim->tolerances = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	if (!sim->y || !sim->y_saved || !sim->tolerances)
		goto out_of_memory;
	// Before CVodeInit: every vector CVODE and the solvers clone from y inherits the operations.
	sm_vector_ops_install(sim->y);
	sm_vector_ops_install(sim->y_saved);
	sm_vector_ops_install(sim->tolerances);
	load_initial_state(sim);
	sm_status st = setup_cvode(sim);
	if (st != SM_OK) {
		sm_error_set(err, st, "simulation: cannot set up CVODE with the %s linear solver%s%s",
		             sm_linear_solver_name(sim->solver), sim->solver_message[0] ? ": " : "",
		             sim->solver_message);
		sm_simulation_destroy(sim);
		return NULL;
	}
	return sim;

out_of_memory:
	sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "simulation: out of memory for a model of %d particles",
	             (int)model->particle_count);
	sm_simulation_destroy(sim);
	return NULL;
}

void sm_simulation_destroy(sm_simulation* sim)
{
	if (sim == NULL)
		return;
	if (sim->cvode)
		CVodeFree(&sim->cvode);
	SUNLinSolFree(sim->linear_solver);
	if (sim->fixed_point)
		SUNNonlinSolFree(sim->fixed_point);
	SUNMatDestroy(sim->matrix);
	N_VDestroy(sim->y);
	N_VDestroy(sim->y_saved);
	N_VDestroy(sim->tolerances);
	sm_simulation_free_events(sim);  // before the context its vector belongs to
	if (sim->context)
		SUNContext_Free(&sim->context);
	sm_model_destroy(sim->model);
	sm_sparse_jacobian_destroy(sim->pattern);
	free(sim->dfdx);
	free(sim->dfdv);
	free(sim->klu_row_pointers);
	free(sim->klu_column_indices);
	sm_spring_jacobians_destroy(sim->jacobian_records);
	free(sim->initial_enabled);
	free(sim->free_particles);
	free(sim->constrained);
	free(sim->inverse_mass);
	free(sim->mass_dof);
	free(sim->position);
	free(sim->velocity);
	free(sim->external_force);
	free(sim->drive_position);
	free(sim->drive_velocity);
	free(sim->drive_acceleration);
	free(sim->drive_time);
	free(sim->origin_slot);
	free(sim->origins);
	free(sim->force_rate);
	free(sim->force_time);
	free(sim->work_external);
	free(sim->driven_spring_start);
	free(sim->driven_springs);
	free(sim->work_position);
	free(sim->work_velocity);
	free(sim->work_force);
	free(sim->breaks);
	free(sim);
}

// ---------------------------------------------------------------------------------------------
// Advancing
// ---------------------------------------------------------------------------------------------

// Adds CVODE's counters (which CVodeReInit clears) to the base.
static void fold_counters(sm_simulation* sim)
{
	long steps = 0, error_fails = 0, conv_fails = 0;
	CVodeGetNumSteps(sim->cvode, &steps);
	CVodeGetNumErrTestFails(sim->cvode, &error_fails);
	CVodeGetNumNonlinSolvConvFails(sim->cvode, &conv_fails);
	sim->base.steps += steps;
	sim->base.error_test_failures += error_fails;
	sim->base.convergence_failures += conv_fails;
}

// Re-initialises CVODE at the current state: a restart (counted in the statistics), or for a
// reset, which is not counted and starts the linear solver as new. A restart keeps the cholmod
// solver's factor of an earlier Newton matrix (a restart at every input change would otherwise
// refactorise at every communication step), but not after a restore, which starts it as new too:
// the run after a restore is then the same, bit for bit, whatever the simulation did before.
static sm_status reinit(sm_simulation* sim, bool reset)
{
	fold_counters(sim);
	if (!reset)
		sim->base.restarts++;
	sim->need_restart = false;
	sim->input_jumped = false;
	sim->break_pending = false;
	if (has_reduced_solver(sim))
		sm_reduced_solver_invalidate(sim->linear_solver, reset || sim->forget_factor);
	sim->forget_factor = false;
	sim->time_origin = sim->time;
	if (CVodeReInit(sim->cvode, 0.0, sim->y) != CV_SUCCESS) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(sim->time, t);
		return sm_simulation_fail(sim, SM_ERROR_SOLVER, "cannot re-initialise CVODE at t = %s s: %s", t,
		                          sim->solver_message);
	}
	return SM_OK;
}

// The name of a CVode failure flag. CVodeGetReturnFlagName would allocate it, and SUNDIALS 6.4.1
// writes into that allocation without checking it: out of memory, a failed advance crashed there.
#define FLAG_CASE(flag)                                                                                      \
	case flag: return #flag
static const char* failure_name(int flag)
{
	switch (flag) {
		FLAG_CASE(CV_TOO_MUCH_WORK);
		FLAG_CASE(CV_TOO_MUCH_ACC);
		FLAG_CASE(CV_ERR_FAILURE);
		FLAG_CASE(CV_CONV_FAILURE);
		FLAG_CASE(CV_LINIT_FAIL);
		FLAG_CASE(CV_LSETUP_FAIL);
		FLAG_CASE(CV_LSOLVE_FAIL);
		FLAG_CASE(CV_RHSFUNC_FAIL);
		FLAG_CASE(CV_FIRST_RHSFUNC_ERR);
		FLAG_CASE(CV_REPTD_RHSFUNC_ERR);
		FLAG_CASE(CV_UNREC_RHSFUNC_ERR);
		FLAG_CASE(CV_RTFUNC_FAIL);
		FLAG_CASE(CV_NLS_INIT_FAIL);
		FLAG_CASE(CV_NLS_SETUP_FAIL);
		FLAG_CASE(CV_CONSTR_FAIL);
		FLAG_CASE(CV_NLS_FAIL);
		FLAG_CASE(CV_MEM_FAIL);
		FLAG_CASE(CV_MEM_NULL);
		FLAG_CASE(CV_ILL_INPUT);
		FLAG_CASE(CV_NO_MALLOC);
		FLAG_CASE(CV_BAD_T);
		FLAG_CASE(CV_TOO_CLOSE);
		FLAG_CASE(CV_VECTOROP_ERR);
		FLAG_CASE(CV_CONTEXT_ERR);
	default: return "an unknown flag";
	}
}
#undef FLAG_CASE

// What a failure of CVODE means for the model, in its terms.
static const char* failure_hint(int flag)
{
	switch (flag) {
	case CV_TOO_MUCH_WORK:
		return " (the max_steps internal steps allowed per advance were not enough: raise max_steps (a model "
		       "file's \"max_steps\", springmass run --max-steps, an FMU's solver.max_steps), or look for a spring "
		       "much stiffer than the others or a huge force)";
	case CV_RHSFUNC_FAIL:
	case CV_FIRST_RHSFUNC_ERR:
	case CV_REPTD_RHSFUNC_ERR:
	case CV_UNREC_RHSFUNC_ERR:
		return " (the state or the forces became non-finite: look for huge or tiny masses, stiffnesses, "
		       "velocities, positions or inputs)";
	case CV_ERR_FAILURE:
	case CV_CONV_FAILURE:
		return " (the step size fell to round-off: the model moves faster than the tolerances can follow, or "
		       "its forces jump)";
	default: return "";
	}
}

// An interval too short for CVODE: one explicit Euler step y += (t_end - t) y'(t), exact to
// O(dt^2), that is to round-off at this scale. CVODE keeps its history (or restarts from here if
// it has to) at the next advance.
static sm_status short_step(sm_simulation* sim, double t_end)
{
	const double dt = t_end - sim->time;
	if (dt <= 0.0)
		return SM_OK;
	// A restart is due: the springs' constants may have changed since CVODE's last step (a break,
	// a restore, a model update), and the reduced solver's right-hand side evaluates its copies of
	// them, which it takes afresh at an invalidation. The restart would make one; this step comes
	// before it.
	if (sim->need_restart && has_reduced_solver(sim))
		sm_reduced_solver_invalidate(sim->linear_solver, false);
	if (rhs(sm_simulation_cvode_time(sim, sim->time), sim->y, sim->y_saved, sim) != 0) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(sim->time, t);
		return sm_simulation_fail(
		    sim, SM_ERROR_SOLVER,
		    "advance: the state or the forces at t = %s s are not finite (advancing by %.3g s)", t, dt);
	}
	N_VLinearSum(1.0, sim->y, dt, sim->y_saved, sim->y);
	sim->time = t_end;
	sm_simulation_refresh_outputs(sim);
	return SM_OK;
}

// CVODE's first step comes out as 0 when the weighted norms of the accelerations overflow
// (about 1e302 m/s^2 at atol 1e-6 m/s); CVODE then reports success at the stop time, having
// moved nothing (it interpolates with h = 0). A step of size 0 is a failure; *reached becomes
// NaN so that the state from before the call is kept.
static int check_step_size(sm_simulation* sim, int flag, double* reached)
{
	double h = 0.0;
	if (flag < 0 || flag == CV_ROOT_RETURN || (CVodeGetLastStep(sim->cvode, &h) == CV_SUCCESS && h > 0.0))
		return flag;
	*reached = NAN;
	sm_format_c_locale(
	    sim->solver_message, sizeof sim->solver_message,
	    "the step size is 0 s at t = %g s: the accelerations are too large to measure against the tolerances",
	    sim->time);
	return CV_ERR_FAILURE;
}

// CVODE's own time t_n (on its axis): past the simulation's time after an advance that
// interpolated its end (sm_simulation_advance_interpolated), at it otherwise (or within CVODE's
// round-off of a stop time).
static double cvode_time(const sm_simulation* sim)
{
	double t = sm_simulation_cvode_time(sim, sim->time);
	if (!sim->need_restart)
		CVodeGetCurrentTime(sim->cvode, &t);
	return t;
}

// Whether CVODE has stepped past the simulation's time. Its steps beyond were taken with the
// inputs as they were: a changed input must restart it at the simulation's time.
static bool cvode_ahead(const sm_simulation* sim)
{
	return !sim->need_restart && cvode_time(sim) > sm_simulation_cvode_time(sim, sim->time);
}

// The simulation's time of CVODE's time `cvode_t` in an advance to t_end (cvode_end on CVODE's
// axis): t_end itself there, never past it.
static double time_of(const sm_simulation* sim, double cvode_t, double cvode_end, double t_end)
{
	return cvode_t >= cvode_end ? t_end : fmin(sim->time_origin + cvode_t, t_end);
}

// One internal step per CVode call until CVODE's time reaches t_end, never past t_stop, the
// caller told of each step (on_step); no step if CVODE is there already. With t_stop = t_end
// these are the steps of CV_NORMAL, which loops over them inside CVODE up to the stop time. With
// t_stop past t_end (sm_simulation_advance_interpolated) CVODE looks for roots over each whole
// step, t_end or not, so that the roots are those of one advance to t_stop, bit for bit, and
// the caller interpolates t_end. CVODE counts its step limit within one call, so the limit,
// `allowed` steps, is kept here, as CV_NORMAL would. Models with breakable springs always step
// this way: each step is searched for a strain that crosses its limit inside it
// (sm_simulation_search_step), which CVODE's root functions, compared at the ends of its steps,
// miss. *reached is where CVODE stopped: the end of its last step, a break (CVODE's root or a
// crossing inside the step), or the last state it reached on failure (in y). All times are CVODE's.
static int step_one_at_a_time(sm_simulation* sim, double t_end, double t_stop, long allowed, double* reached)
{
	*reached = cvode_time(sim);
	if (*reached >= t_end)
		return CV_SUCCESS;
	CVodeSetStopTime(sim->cvode, t_stop);
	// In one-step mode tout only sizes CVODE's first step after a (re)initialisation, from the
	// interval to it (at least 100 eps |tout|): a stop time far beyond any run (a master's 1e28 s
	// for "no end") made that step too large to converge, every time. It is the stop time up to
	// STOP_HORIZON ahead, as in one advance to it, whatever the output times and restarts.
	const double tout = t_stop - *reached > STOP_HORIZON ? *reached + STOP_HORIZON : t_stop;
	long steps = 0;
	int flag = CV_SUCCESS;
	while (flag == CV_SUCCESS && *reached < t_end && steps < allowed && !sim->stopped) {
		long steps_before = 0, steps_after = 0;
		CVodeGetNumSteps(sim->cvode, &steps_before);
		flag = check_step_size(sim, CVode(sim->cvode, tout, sim->y, reached, CV_ONE_STEP), reached);
		CVodeGetNumSteps(sim->cvode, &steps_after);
		// A spring that reached its break strain inside the step ends it there, as a root does.
		flag = sm_simulation_search_step(sim, flag, steps_after > steps_before, reached);
		if (flag >= 0 && sim->def.on_step != NULL &&
		    !sim->def.on_step(sim->def.on_step_context, sim->time_origin + *reached))
			sim->stopped = true;
		steps++;
	}
	return flag;
}

// The state at CVODE's time cvode_t, the simulation's time t, from CVODE's history of its last
// step (its interpolating polynomial, of the order of the step), into y.
static sm_status interpolate(sm_simulation* sim, double cvode_t, double t)
{
	if (CVodeGetDky(sim->cvode, cvode_t, 0, sim->y) != CV_SUCCESS) {
		char at[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(t, at);
		sim->need_restart = true;
		N_VScale(1.0, sim->y_saved, sim->y);
		sm_simulation_refresh_outputs(sim);
		return sm_simulation_fail(sim, SM_ERROR_SOLVER, "CVODE cannot interpolate its state at t = %s s: %s",
		                          at, sim->solver_message);
	}
	sim->time = t;
	return SM_OK;
}

// The end of an advance that the caller's on_step stopped at the simulation's time.
static sm_status stopped_by_caller(sm_simulation* sim, double t_end)
{
	sm_simulation_refresh_outputs(sim);
	char now[SM_NUMBER_TEXT_CAPACITY], end[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(sim->time, now);
	sm_format_number(t_end, end);
	return sm_simulation_fail(sim, SM_ERROR_STEP_LIMIT,
	                          "stopped by on_step at t = %s s while advancing to %s s", now, end);
}

static sm_status advance(sm_simulation* sim, double t_end, double t_stop)
{
	sim->last_error[0] = '\0';
	// To the current time: nothing, not even taking the inputs changed as seen by an advance.
	if (!(sim->time < t_end))
		return SM_OK;
	sm_input_origins_forget(sim);  // the inputs now are those of this advance
	// Inputs that changed for this advance will likely change at its end too (a co-simulation
	// master's): CVODE then ends its last step at t_end rather than step past it.
	const bool inputs_changed = sim->input_changed;
	sim->input_changed = false;
	// Where CVODE is past the current time, it has looked for roots beyond it already, on the
	// same trajectory: springs are checked afresh only where it starts or restarts.
	if (!cvode_ahead(sim) && sm_simulation_break_overstretched_springs(sim) != SM_OK)
		return SM_ERROR_OUT_OF_MEMORY;
	// CVODE steps on to t_stop, or ends its last step at t_end when the inputs changed: an interval
	// up to there too short for it is one step of our own. Too short on CVODE's time axis, which
	// starts at 0 at the restart due here: at t = 1e14 s an ulp of t, 0.016 s, is a step CVODE
	// takes, and far too long for one explicit step.
	const double t_last = inputs_changed ? t_end : t_stop;
	const double cvode_now = sim->need_restart ? 0.0 : sm_simulation_cvode_time(sim, sim->time);
	if (!cvode_ahead(sim) && t_last - sim->time < TIME_RESOLUTION * fmax(1.0, fabs(cvode_now)))
		return short_step(sim, t_end);
	// max_steps holds for the whole advance: over the CVode calls between spring breaks and
	// restarts too, each of which CVODE would count afresh.
	long steps_taken = 0;
	while (sim->time < t_end) {
		if (sim->need_restart) {
			sm_status st = reinit(sim, false);
			if (st != SM_OK)
				return st;
		}
		// The end and the stop time on CVODE's axis, which a restart moves.
		const double cvode_end = sm_simulation_cvode_time(sim, t_end);
		const double cvode_stop = sm_simulation_cvode_time(sim, t_stop);
		N_VScale(1.0, sim->y, sim->y_saved);
		if (sim->break_pending) {
			// A spring break that CVODE found past the end of the last advance: interpolate up
			// to it, then break it there.
			const bool beyond = sim->break_time > cvode_end;
			sm_status st =
			    beyond ? interpolate(sim, cvode_end, t_end)
				       : interpolate(sim, sim->break_time, time_of(sim, sim->break_time, cvode_end, t_end));
			if (st != SM_OK)
				return st;
			if (beyond)
				break;
			sim->break_pending = false;
			if (sm_simulation_break_springs(sim) != SM_OK)
				return SM_ERROR_OUT_OF_MEMORY;
			continue;
		}
		sim->solver_message[0] = '\0';
		sim->jacobian_out_of_memory = false;
		const bool past_end = (t_stop > t_end && !inputs_changed) || cvode_ahead(sim);
		double reached = sm_simulation_cvode_time(sim, sim->time);  // CVODE's time
		const long allowed = (long)sim->def.max_steps - steps_taken;
		long steps_before = 0, steps_after = 0;
		CVodeGetNumSteps(sim->cvode, &steps_before);
		int flag;
		if (allowed <= 0) {
			flag = CV_SUCCESS;  // reported as too much work below
		} else if (!past_end && sim->def.on_step == NULL && sim->root_count == 0 &&
		           cvode_end - reached <= STOP_HORIZON) {
			CVodeSetStopTime(sim->cvode, cvode_end);
			CVodeSetMaxNumSteps(sim->cvode, allowed);
			flag = check_step_size(sim, CVode(sim->cvode, cvode_end, sim->y, &reached, CV_NORMAL), &reached);
		} else {
			flag = step_one_at_a_time(sim, cvode_end, past_end ? cvode_stop : cvode_end, allowed, &reached);
		}
		CVodeGetNumSteps(sim->cvode, &steps_after);
		steps_taken += steps_after - steps_before;
		// The caller's on_step asked to stop: CVODE's last step is complete and its history intact,
		// so the advance ends there (after a break found at it) and the next goes on from it.
		const bool stop = sim->stopped;
		sim->stopped = false;
		if (flag == CV_SUCCESS && reached < cvode_end && stop) {
			sim->time = time_of(sim, reached, cvode_end, t_end);
			return stopped_by_caller(sim, t_end);
		}
		if (flag == CV_SUCCESS && reached < cvode_end) {
			flag = CV_TOO_MUCH_WORK;
			sm_format_c_locale(sim->solver_message, sizeof sim->solver_message,
			                   "CVode: At t = %g, mxstep steps taken before reaching tout.",
			                   sim->time_origin + reached);
		}
		if (flag < 0 && flag != CV_TOO_MUCH_WORK && sim->input_jumped) {
			// An input jumped and CVODE kept its history over it, but its error control could not
			// absorb the jump: start afresh at the jump (the state before this call, at the
			// input's time) and try once more, as a restart at the change would have done.
			N_VScale(1.0, sim->y_saved, sim->y);
			sim->need_restart = true;
			continue;
		}
		if (flag < 0) {
			// CVODE leaves the last state it reached in y; keep the state from before the call
			// if that is not usable. Without a step taken there is nothing newer, and y is not that
			// state: a failure in the choice of the first step leaves a trial state there, and one in
			// the first step the predicted state taken back, which loses the state's low bits to the
			// prediction's, and all of them when the prediction is far larger (a velocity of 1 m/s
			// became 0 after a trial with an acceleration of 1e100 m/s^2).
			const double* y = N_VGetArrayPointer(sim->y);
			bool usable = isfinite(reached) && reached >= sm_simulation_cvode_time(sim, sim->time) &&
			              reached <= cvode_end;
			for (int64_t i = 0; usable && i < sm_simulation_state_length(sim); i++)
				usable = isfinite(y[i]);
			if (usable && steps_after > steps_before)
				sim->time = time_of(sim, reached, cvode_end, t_end);
			else
				N_VScale(1.0, sim->y_saved, sim->y);
			// After too much work CVODE may simply go on; after any other failure it starts
			// afresh from the last good state.
			sim->need_restart = flag != CV_TOO_MUCH_WORK || !usable;
			sm_simulation_refresh_outputs(sim);
			if (flag == CV_LSETUP_FAIL && sim->jacobian_out_of_memory)
				snprintf(sim->solver_message, sizeof sim->solver_message,
				         "out of memory evaluating the Jacobian");
			// The reduced solver says why its solve failed in its last flag.
			if (flag == CV_LSOLVE_FAIL && has_reduced_solver(sim) &&
			    SUNLinSolLastFlag(sim->linear_solver) == SUNLS_MEM_FAIL)
				snprintf(sim->solver_message, sizeof sim->solver_message,
				         "out of memory in the linear solve");
			char now[SM_NUMBER_TEXT_CAPACITY], end[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(sim->time, now);
			sm_format_number(t_end, end);
			// Too much work is no failure of the method: the state is good and the next advance
			// goes on from it.
			if (flag == CV_TOO_MUCH_WORK && usable)
				return sm_simulation_fail(
				    sim, SM_ERROR_STEP_LIMIT,
				    "CVODE stopped at its step limit (CV_TOO_MUCH_WORK) at t = %s s while advancing to %s s; "
				    "the state there is good and the next advance goes on from it%s",
				    now, end, failure_hint(flag));
			if (usable)
				return sm_simulation_fail(sim, SM_ERROR_SOLVER,
				                          "CVODE failed with %s at t = %s s while advancing to %s s%s%s%s",
				                          failure_name(flag), now, end, failure_hint(flag),
				                          sim->solver_message[0] ? ": " : "", sim->solver_message);
			// CVODE's last state is not finite: the message gives the time the simulation stays at.
			return sm_simulation_fail(
			    sim, SM_ERROR_SOLVER,
			    "CVODE failed with %s while advancing to %s s; the state it reached is not usable, so the "
			    "simulation stays at its last good state, t = %s s%s%s%s",
			    failure_name(flag), end, now, failure_hint(flag), sim->solver_message[0] ? ": " : "",
			    sim->solver_message);
		}
		if (flag == CV_ROOT_RETURN && reached > cvode_end) {
			// A break past the end: kept for the next advance, where CVODE's history still
			// reaches it unless an input, the state or the model changes first.
			sim->break_pending = true;
			sim->break_time = reached;
			sm_status st = interpolate(sim, cvode_end, t_end);
			if (st != SM_OK)
				return st;
		} else if (flag == CV_ROOT_RETURN) {
			sim->time = time_of(sim, reached, cvode_end, t_end);
			if (sm_simulation_break_springs(sim) != SM_OK)
				return SM_ERROR_OUT_OF_MEMORY;
		} else if (past_end) {
			// CVODE's last step ends at or past t_end, in this call or an earlier one.
			sm_status st = interpolate(sim, cvode_end, t_end);
			if (st != SM_OK)
				return st;
		} else {
			sim->time = t_end;
		}
		if (stop && sim->time < t_end)
			return stopped_by_caller(sim, t_end);
	}
	sm_simulation_refresh_outputs(sim);
	return SM_OK;
}

// Refuses an end time that is not finite or lies before the current time, and a stop time that
// is not finite or lies before the end time, with nothing changed.
static sm_status check_times(sm_simulation* sim, const char* function, double t_end, double t_stop)
{
	const bool bad_end = !isfinite(t_end) || t_end < sim->time;
	if (!bad_end && isfinite(t_stop) && t_stop >= t_end)
		return SM_OK;
	char end[SM_NUMBER_TEXT_CAPACITY], other[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(t_end, end);
	sm_format_number(bad_end ? sim->time : t_stop, other);
	if (bad_end)
		return sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT,
		                          "%s: end time %s s must be finite and not before the current time %s s",
		                          function, end, other);
	return sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT,
	                          "%s: stop time %s s must be finite and not before the end time %s s", function,
	                          other, end);
}

sm_status sm_simulation_advance(sm_simulation* sim, double t_end)
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sm_status st = check_times(sim, "advance", t_end, t_end);
	return st != SM_OK ? st : advance(sim, t_end, t_end);
}

sm_status sm_simulation_advance_interpolated(sm_simulation* sim, double t_end, double t_stop)
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sm_status st = check_times(sim, "advance_interpolated", t_end, t_stop);
	return st != SM_OK ? st : advance(sim, t_end, t_stop);
}

// ---------------------------------------------------------------------------------------------
// Access
// ---------------------------------------------------------------------------------------------

double sm_simulation_time(const sm_simulation* sim)
{
	return sim ? sim->time : NAN;
}

const double* sm_simulation_positions(const sm_simulation* sim)
{
	return sim ? sim->position : NULL;
}

const double* sm_simulation_velocities(const sm_simulation* sim)
{
	return sim ? sim->velocity : NULL;
}

void sm_simulation_forces(const sm_simulation* sim, double* f)
{
	if (sim == NULL || f == NULL)
		return;
	if (sim->ramping_forces == 0) {
		sm_model_forces(sim->model, sim->position, sim->velocity, sim->external_force, f);
		return;
	}
	sm_model_forces(sim->model, sim->position, sim->velocity, NULL, f);
	for (int32_t i = 0; i < sim->particle_count; i++) {
		const size_t p = 3 * (size_t)i;
		const double dt = sim->time - sim->force_time[i];
		for (int c = 0; c < 3; c++)
			f[p + c] += sim->external_force[p + c] + sim->force_rate[p + c] * dt;
	}
}

sm_energies sm_simulation_energies(const sm_simulation* sim)
{
	if (sim == NULL) {
		sm_energies e = {NAN, NAN, NAN};
		return e;
	}
	return sm_model_energies(sim->model, sim->position, sim->velocity);
}

double sm_simulation_dissipated_energy(const sm_simulation* sim)
{
	return sim ? N_VGetArrayPointer(sim->y)[sm_simulation_dissipated_index(sim)] : NAN;
}

double sm_simulation_input_work(const sm_simulation* sim)
{
	return sim ? N_VGetArrayPointer(sim->y)[sm_simulation_work_index(sim)] + sim->jump_work : NAN;
}

double sm_simulation_input_power(sm_simulation* sim)
{
	if (sim == NULL)
		return NAN;
	const double* external = sm_simulation_external_forces(sim, sm_simulation_cvode_time(sim, sim->time));
	sm_model_forces(sim->model, sim->position, sim->velocity, external, sim->work_force);
	return input_power(sim, sim->velocity, sim->work_force, external);
}

const sm_model* sm_simulation_model(const sm_simulation* sim)
{
	return sim ? sim->model : NULL;
}

sm_statistics sm_simulation_statistics(const sm_simulation* sim)
{
	sm_statistics s;
	memset(&s, 0, sizeof s);
	if (sim == NULL)
		return s;
	s = sim->base;
	long steps = 0, error_fails = 0, conv_fails = 0;
	CVodeGetNumSteps(sim->cvode, &steps);
	CVodeGetNumErrTestFails(sim->cvode, &error_fails);
	CVodeGetNumNonlinSolvConvFails(sim->cvode, &conv_fails);
	s.steps += steps;
	s.error_test_failures += error_fails;
	s.convergence_failures += conv_fails;
	s.rhs_evaluations = sim->rhs_evaluations;
	s.jacobian_evaluations = sim->jacobian_evaluations;
	s.linear_iterations = sim->linear_iterations;
	s.factorizations = sim->factorizations;
	return s;
}

int32_t sm_simulation_break_count(const sm_simulation* sim)
{
	return sim ? sim->break_count : 0;
}

sm_break_event sm_simulation_break(const sm_simulation* sim, int32_t index)
{
	sm_break_event e = {NAN, -1};
	if (sim && index >= 0 && index < sim->break_count)
		e = sim->breaks[index];
	return e;
}

sm_linear_solver sm_simulation_solver(const sm_simulation* sim)
{
	return sim ? sim->solver : SM_SOLVER_COUNT;
}

const char* sm_simulation_last_error(const sm_simulation* sim)
{
	return sim ? sim->last_error : "simulation is NULL";
}

// ---------------------------------------------------------------------------------------------
// Changes between calls
// ---------------------------------------------------------------------------------------------

static bool finite3(const double* a)
{
	return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]);
}

// Whether a value given at a time t (16 units of round-off of the largest term) lies on the path
// value + change a call at t - dt set, where change is the sum of terms of which the largest is
// `term` in size: a caller's x0 + v t and the path's own x0 + v dt, summed over steps, part in the
// last bits; x0 + v0 t + a t^2 / 2 and x0 + t (v0 + t a / 2) part by round-off of v0 t and a t^2 / 2,
// however much of them cancels. A constant (change and term 0) within round-off is on its path too:
// a master that interpolates a held signal between two samples, w0 v + w1 v, is an ulp off at times.
static bool on_path(double given, double value, double change, double term)
{
	const double path = value + change;
	const double scale = fmax(fmax(fabs(given), fabs(value)), fmax(fabs(change), term));
	return fabs(given - path) <= 16.0 * DBL_EPSILON * scale;
}

// Whether a driven particle's position, velocity and acceleration given now lie on the path
// (x0, v0, a0) that started dt ago (on_path: however the caller summed it).
static bool on_driven_path(const double* x0, const double* v0, const double* a0, double dt,
                           const double* position, const double* velocity, const double* acceleration)
{
	for (int c = 0; c < 3; c++) {
		const double a = a0[c];
		if (acceleration[c] != a || !on_path(velocity[c], v0[c], a * dt, fabs(a * dt)) ||
		    !on_path(position[c], x0[c], dt * (v0[c] + 0.5 * dt * a),
		             fmax(fabs(v0[c] * dt), fabs(0.5 * dt * dt * a))))
			return false;
	}
	return true;
}

// Whether an external force and rate given now lie on the ramp (f0, r0) that started dt ago.
static bool on_force_ramp(const double* f0, const double* r0, double dt, const double* force,
                          const double* rate)
{
	for (int c = 0; c < 3; c++)
		if (rate[c] != r0[c] || !on_path(force[c], f0[c], r0[c] * dt, fabs(r0[c] * dt)))
			return false;
	return true;
}

// After an input changed at the current time: CVODE restarts here when the options ask for it or
// when it has stepped past (its steps assumed the input as it was).
static void note_input_change(sm_simulation* sim)
{
	sim->input_jumped = true;
	sim->input_changed = true;
	if (sim->def.restart_on_input_change || cvode_ahead(sim))
		sim->need_restart = true;
}

sm_status sm_simulation_set_driven(sm_simulation* sim, int32_t particle, const double position[3],
                                   const double velocity[3])
{
	static const double none[3] = {0.0, 0.0, 0.0};
	return sm_simulation_set_driven_accelerating(sim, particle, position, velocity, none);
}

sm_status sm_simulation_set_driven_accelerating(sm_simulation* sim, int32_t particle,
                                                const double position[3], const double velocity[3],
                                                const double acceleration[3])
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	if (particle < 0 || particle >= sim->particle_count)
		return sm_simulation_fail(sim, SM_ERROR_PARTICLE_INDEX,
		                          "set_driven: particle %d is out of range (the model has %d)", (int)particle,
		                          (int)sim->particle_count);
	if (sim->model->motion[particle] != SM_PARTICLE_DRIVEN)
		return sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT, "set_driven: particle %d is not driven",
		                          (int)particle);
	if (position == NULL || velocity == NULL || acceleration == NULL)
		return sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT, "set_driven: particle %d: %s is NULL",
		                          (int)particle,
		                          position == NULL   ? "position"
		                          : velocity == NULL ? "velocity"
		                                             : "acceleration");
	if (!finite3(position) || !finite3(velocity) || !finite3(acceleration))
		return sm_simulation_fail(sim, SM_ERROR_NOT_FINITE,
		                          "set_driven: particle %d: position, velocity and acceleration must be 3 "
		                          "finite numbers each",
		                          (int)particle);
	const size_t p = 3 * (size_t)particle;
	// The same acceleration with a position and a velocity on the current path is no jump, and keeps
	// the path as it was, so that the run is that of no call, to the bit.
	if (on_driven_path(sim->drive_position + p, sim->drive_velocity + p, sim->drive_acceleration + p,
	                   sim->time - sim->drive_time[particle], position, velocity, acceleration)) {
		sm_simulation_refresh_outputs(sim);
		return SM_OK;
	}
	// Back on the path it had before its first change since the last advance: that path again, to
	// the bit, and once every input is back, no change at all (input_origins.c).
	const sm_input_origin* found = sm_input_origins_find(sim, particle);
	const bool back =
	    found != NULL && on_driven_path(found->value, found->rate, found->acceleration,
		                                sim->time - found->time, position, velocity, acceleration);
	sm_input_origin origin;
	if (back)
		origin = *found;
	else
		sm_input_origins_note(sim, particle, true);
	// What moves the particle to its new position and velocity at once does the work the energy
	// takes in the jump. An energy beyond a double is not handed on to the inputs' work.
	const int32_t* springs = sim->driven_springs + sim->driven_spring_start[particle];
	const int32_t count = sim->driven_spring_start[particle + 1] - sim->driven_spring_start[particle];
	const double before =
	    sm_model_particle_energy(sim->model, sim->position, sim->velocity, particle, springs, count);
	memcpy(sim->drive_position + p, back ? origin.value : position, 3 * sizeof(double));
	memcpy(sim->drive_velocity + p, back ? origin.rate : velocity, 3 * sizeof(double));
	memcpy(sim->drive_acceleration + p, back ? origin.acceleration : acceleration, 3 * sizeof(double));
	sim->drive_time[particle] = back ? origin.time : sim->time;
	const bool undone = back && sm_input_origins_settle(sim, particle);
	if (!undone)
		note_input_change(sim);
	sm_simulation_refresh_outputs(sim);
	const double work =
	    sm_model_particle_energy(sim->model, sim->position, sim->velocity, particle, springs, count) - before;
	if (!undone && isfinite(work))
		sim->jump_work += work;
	return SM_OK;
}

sm_status sm_simulation_set_external_force(sm_simulation* sim, int32_t particle, const double force[3])
{
	static const double none[3] = {0.0, 0.0, 0.0};
	return sm_simulation_set_external_force_ramp(sim, particle, force, none);
}

sm_status sm_simulation_set_external_force_ramp(sm_simulation* sim, int32_t particle, const double force[3],
                                                const double rate[3])
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	if (particle < 0 || particle >= sim->particle_count)
		return sm_simulation_fail(sim, SM_ERROR_PARTICLE_INDEX,
		                          "set_external_force: particle %d is out of range (the model has %d)",
		                          (int)particle, (int)sim->particle_count);
	if (force == NULL || rate == NULL)
		return sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT,
		                          "set_external_force: particle %d: %s is NULL", (int)particle,
		                          force == NULL ? "force" : "rate");
	if (!finite3(force) || !finite3(rate))
		return sm_simulation_fail(
		    sim, SM_ERROR_NOT_FINITE,
		    "set_external_force: particle %d: force and rate must be 3 finite numbers each", (int)particle);
	// The same rate with a force on the current ramp is no change; a held particle's force moves
	// nothing, so it is none either (the reaction it adds is read as it is).
	double* f = sim->external_force + 3 * (size_t)particle;
	double* r = sim->force_rate + 3 * (size_t)particle;
	if (on_force_ramp(f, r, sim->time - sim->force_time[particle], force, rate))
		return SM_OK;
	const bool free = sim->model->motion[particle] == SM_PARTICLE_FREE;
	// Back on the ramp it had before its first change since the last advance: that ramp again, to
	// the bit, and once every input is back, no change at all (input_origins.c).
	const sm_input_origin* found = free ? sm_input_origins_find(sim, particle) : NULL;
	const bool back =
	    found != NULL && on_force_ramp(found->value, found->rate, sim->time - found->time, force, rate);
	sm_input_origin origin;
	if (back) {
		origin = *found;
		force = origin.value;
		rate = origin.rate;
	} else if (free) {
		sm_input_origins_note(sim, particle, false);
	}
	const bool ramped = r[0] != 0.0 || r[1] != 0.0 || r[2] != 0.0;
	const bool ramps = rate[0] != 0.0 || rate[1] != 0.0 || rate[2] != 0.0;
	const bool forced = ramped || f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0;
	const bool forces = ramps || force[0] != 0.0 || force[1] != 0.0 || force[2] != 0.0;
	sim->ramping_forces += (int32_t)ramps - (int32_t)ramped;
	sim->forced_particles += free ? (int32_t)forces - (int32_t)forced : 0;
	memcpy(f, force, 3 * sizeof(double));
	memcpy(r, rate, 3 * sizeof(double));
	sim->force_time[particle] = back ? origin.time : sim->time;
	if (free && !(back && sm_input_origins_settle(sim, particle)))
		note_input_change(sim);
	return SM_OK;
}

// Particle i's position at the simulation's time, as sm_simulation_refresh_outputs puts it in
// sim->position, without unpacking every particle.
static void position_now(const sm_simulation* sim, int32_t i, double x[3])
{
	const sm_model* m = sim->model;
	const int32_t k = m->free_index[i];
	if (k >= 0)
		memcpy(x, N_VGetArrayPointer(sim->y) + 3 * (size_t)k, 3 * sizeof(double));
	else if (m->motion[i] == SM_PARTICLE_DRIVEN)
		driven_state(sim, i, sm_simulation_cvode_time(sim, sim->time), x, NULL);
	else
		memcpy(x, m->position + 3 * (size_t)i, 3 * sizeof(double));
}

// A break the caller decides on (a cut, a tear it models itself), as sm_simulation_break_springs makes one
// when a strain crosses its limit: recorded, its elastic energy moved to the dissipated energy,
// CVODE restarted here (what it computed past this time assumed the spring). Its cost does not grow
// with the model (the restart comes once, at the next advance), so that cutting k springs of a large
// model costs k breaks and one restart.
sm_status sm_simulation_break_spring(sm_simulation* sim, int32_t spring)
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	if (spring < 0 || spring >= sm_model_spring_count(sim->model))
		return sm_simulation_fail(sim, SM_ERROR_SPRING_INDEX,
		                          "break_spring: spring %d is out of range (the model has %d)", (int)spring,
		                          (int)sm_model_spring_count(sim->model));
	if (!sim->model->enabled[spring])
		return SM_OK;
	sm_input_origins_forget(sim);  // the restart it asks for stays, whatever the inputs do
	double xa[3], xb[3];
	position_now(sim, sim->model->spring_a[spring], xa);
	position_now(sim, sim->model->spring_b[spring], xb);
	const double released = sm_model_spring_energy(sim->model, spring, xa, xb);
	if (sm_simulation_record_break(sim, sim->time, spring) != SM_OK)
		return sm_simulation_fail(sim, SM_ERROR_OUT_OF_MEMORY,
		                          "break_spring: out of memory recording the break");
	// As at a break found by the integration (simulation_events.c): an energy beyond a double is
	// not handed on to the dissipated energy, part of CVODE's state.
	if (isfinite(released))
		N_VGetArrayPointer(sim->y)[sm_simulation_dissipated_index(sim)] += released;
	sim->need_restart = true;
	return SM_OK;
}

// Every spring enabled as in the model the simulation was given (create or update_model): those
// that broke restored, those the model disables disabled.
void sm_simulation_restore_springs(sm_simulation* sim)
{
	for (int32_t s = 0; s < sim->spring_count; s++)
		if (sm_model_spring_enabled(sim->model, s) != (sim->initial_enabled[s] != 0))
			sm_model_set_spring_enabled(sim->model, s, sim->initial_enabled[s] != 0);
}

// The first driven particle whose position at time t, x0 + s (v0 + s a / 2) with s = t - t0 as
// sm_simulation_unpack forms it, or whose velocity v0 + s a, is not finite under the given motions
// (3 positions [m], velocities [m/s] and accelerations [m/s^2] per particle, one start time [s]
// per particle), or -1. An advance stops where forces are not finite, so a simulation
// never gets there by itself; a snapshot read back from bytes, or a time given to set_state, may
// hold such a motion and time.
int32_t sm_simulation_overflowing_driven_particle(const sm_simulation* sim, double t, const double* position,
                                                  const double* velocity, const double* acceleration,
                                                  const double* start)
{
	for (int32_t k = 0; k < sim->constrained_count; k++) {
		const int32_t i = sim->constrained[k];
		if (sim->model->motion[i] != SM_PARTICLE_DRIVEN)
			continue;
		const size_t p = 3 * (size_t)i;
		const double dt = t - start[i];
		for (int c = 0; c < 3; c++)
			if (!isfinite(position[p + c] + dt * (velocity[p + c] + 0.5 * dt * acceleration[p + c])) ||
			    !isfinite(velocity[p + c] + dt * acceleration[p + c]))
				return i;
	}
	return -1;
}

// The first particle whose external force at time t, force + rate (t - t0), is not finite under the
// given ramps (3 forces [N] and rates [N/s], one start time [s] per particle), or -1: as for a driven
// particle's position, a snapshot read back from bytes or a time given to set_state may hold one.
int32_t sm_simulation_overflowing_force(const sm_simulation* sim, double t, const double* force,
                                        const double* rate, const double* start)
{
	for (int32_t i = 0; i < sim->particle_count; i++) {
		const size_t p = 3 * (size_t)i;
		for (int c = 0; c < 3; c++)
			if (rate[p + c] != 0.0 && !isfinite(force[p + c] + rate[p + c] * (t - start[i])))
				return i;
	}
	return -1;
}

sm_status sm_simulation_set_state(sm_simulation* sim, double time, const double* x, const double* v)
{
	if (sim == NULL || x == NULL || v == NULL)
		return sim ? sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT,
		                                "set_state: positions and velocities are required")
		           : SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	if (!isfinite(time))
		return sm_simulation_fail(sim, SM_ERROR_NOT_FINITE, "set_state: time %g is not finite", time);
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t p = 3 * (size_t)sim->free_particles[k];
		if (!finite3(x + p) || !finite3(v + p))
			return sm_simulation_fail(sim, SM_ERROR_NOT_FINITE,
			                          "set_state: particle %d: position or velocity is not finite",
			                          (int)sim->free_particles[k]);
	}
	const int32_t overflowing = sm_simulation_overflowing_driven_particle(
	    sim, time, sim->drive_position, sim->drive_velocity, sim->drive_acceleration, sim->drive_time);
	if (overflowing >= 0) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(time, t);
		return sm_simulation_fail(sim, SM_ERROR_NOT_FINITE,
		                          "set_state: driven particle %d's position at t = %s s is not finite",
		                          (int)overflowing, t);
	}
	const int32_t pushed =
	    sm_simulation_overflowing_force(sim, time, sim->external_force, sim->force_rate, sim->force_time);
	if (pushed >= 0) {
		char t[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(time, t);
		return sm_simulation_fail(
		    sim, SM_ERROR_NOT_FINITE,
		    "set_state: particle %d's external force at t = %s s is not finite (its ramp)", (int)pushed, t);
	}
	pack(sim, x, v, N_VGetArrayPointer(sim->y));
	sm_input_origins_forget(sim);
	sim->time = time;
	// CVODE restarts here, at 0 on its axis: the outputs are those of the restart already, not of
	// an axis of the past (a driven particle's position would part from the run's in its last bit).
	sim->time_origin = time;
	sim->need_restart = true;
	sm_simulation_refresh_outputs(sim);
	return SM_OK;
}

sm_status sm_simulation_reset(sm_simulation* sim)
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sm_simulation_restore_springs(sim);
	load_initial_state(sim);
	sm_input_origins_forget(sim);
	sim->break_count = 0;
	sim->input_changed = false;  // the inputs set before the reset are gone with them
	sim->last_error[0] = '\0';
	sm_status st = reinit(sim, true);
	memset(&sim->base, 0, sizeof sim->base);
	sim->rhs_evaluations = sim->jacobian_evaluations = sim->linear_iterations = sim->factorizations = 0;
	return st;
}

sm_status sm_simulation_update_model(sm_simulation* sim, const sm_model* model)
{
	if (sim == NULL || model == NULL)
		return sim ? sm_simulation_fail(sim, SM_ERROR_INVALID_ARGUMENT, "update_model: model is NULL")
		           : SM_ERROR_INVALID_ARGUMENT;
	sim->last_error[0] = '\0';
	const sm_model* old = sim->model;
	if (model->particle_count != old->particle_count || model->spring_count != old->spring_count)
		return sm_simulation_fail(
		    sim, SM_ERROR_TOPOLOGY,
		    "update_model: the new model has %d particles and %d springs, the simulation %d and %d",
		    (int)model->particle_count, (int)model->spring_count, (int)old->particle_count,
		    (int)old->spring_count);
	for (int32_t i = 0; i < model->particle_count; i++)
		if (model->motion[i] != old->motion[i])
			return sm_simulation_fail(sim, SM_ERROR_TOPOLOGY,
			                          "update_model: particle %d moves differently in the new model", (int)i);
	for (int32_t s = 0; s < model->spring_count; s++)
		if (model->spring_a[s] != old->spring_a[s] || model->spring_b[s] != old->spring_b[s] ||
		    model->zero_length[s] != old->zero_length[s])
			return sm_simulation_fail(
			    sim, SM_ERROR_TOPOLOGY,
			    "update_model: spring %d connects other particles or has another kind in the new model",
			    (int)s);
	sm_model* copy = sm_model_clone(model);
	uint8_t* enabled = malloc((size_t)model->spring_count + 1);
	if (!copy || !enabled) {
		sm_model_destroy(copy);
		free(enabled);
		return sm_simulation_fail(sim, SM_ERROR_OUT_OF_MEMORY, "update_model: out of memory");
	}
	if (model->spring_count > 0)
		memcpy(enabled, model->enabled, (size_t)model->spring_count);
	// Springs that broke stay broken. A model made from the simulation's own (cloned, a constant
	// changed) has them disabled too, by the simulation, not by its maker: their state at the
	// start stays as it was, so that a reset restores them. Until the linear solver is rebuilt
	// the copy holds them as at the start: what the solver builds from the constants (the
	// multilevel path groups particles over the strong springs) is then that of a simulation
	// created from the new model, whatever broke before, so that a reset or a restore runs as
	// in one. The breaks are applied after; the solver's copies of the constants are taken
	// afresh at the restart that follows (sm_reduced_solver_invalidate).
	for (int32_t b = 0; b < sim->break_count; b++) {
		const int32_t s = sim->breaks[b].spring;
		enabled[s] = sim->initial_enabled[s];
		sm_model_set_spring_enabled(copy, s, enabled[s] != 0);
	}
	sm_model* previous = sim->model;
	sim->model = copy;
	sim->solver_message[0] = '\0';
	sm_status st = sm_simulation_build_events(sim);
	const char* failure = st == SM_ERROR_OUT_OF_MEMORY ? "update_model: out of memory for the break events"
	                                                   : "update_model: cannot set up the break events";
	if (st == SM_OK && has_reduced_solver(sim) && !sm_reduced_solver_rebuild(sim->linear_solver)) {
		st = SM_ERROR_OUT_OF_MEMORY;
		failure = "update_model: out of memory rebuilding the linear solver";
	}
	if (st != SM_OK) {
		char cause[SM_ERROR_MESSAGE_CAPACITY];
		snprintf(cause, sizeof cause, "%s", sim->solver_message);
		sim->model = previous;
		sm_model_destroy(copy);
		free(enabled);
		sm_simulation_build_events(sim);
		// CVODE's root functions may have been set up anew, and with them went its records of
		// their values and those of a break it found past the current time: it starts afresh
		// here, from the state as it is.
		sim->need_restart = true;
		sm_input_origins_forget(sim);
		return sm_simulation_fail(sim, st, "%s%s%s", failure, cause[0] ? ": " : "", cause);
	}
	for (int32_t b = 0; b < sim->break_count; b++)
		sm_model_set_spring_enabled(copy, sim->breaks[b].spring, false);
	sm_model_destroy(previous);
	free(sim->initial_enabled);
	sim->initial_enabled = enabled;
	refresh_masses(sim);
	sim->need_restart = true;
	sm_input_origins_forget(sim);
	sm_simulation_refresh_outputs(sim);
	return SM_OK;
}

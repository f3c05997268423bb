// Time integration of a model with SUNDIALS CVODE.
//
// This file: the state packed into CVODE's vector and out of it, advancing, access to the state
// and its energies, and changes between calls. Creating a simulation (the definition's defaults
// and check, the choice of the linear solver): simulation_create.c. The right-hand side, the
// Jacobian and the other functions CVODE calls, with the derivation of the state and the
// Jacobian: simulation_callbacks.c.
// Breaking springs: simulation_events.c. State snapshots (save, restore, serialise):
// simulation_state.c.
#define _POSIX_C_SOURCE 200809L

#include "c_locale.h"
#include "law_body_forces.h"
#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_linearsolver.h>

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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
void sm_simulation_pack(const sm_simulation* sim, const double* x, const double* v, double* y)
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
// solver's factor of an earlier Newton matrix for the steps after it that can still use it (the
// short first steps mostly need a new one: it saves about one factorisation in eight when the
// inputs restart it often), but not after a restore, which starts it as new too:
// the run after a restore is then the same, bit for bit, whatever the simulation did before.
static sm_status reinit(sm_simulation* sim, bool reset)
{
	fold_counters(sim);
	if (!reset)
		sim->base.restarts++;
	sim->need_restart = false;
	sim->input_jumped = false;
	sim->break_pending = false;
	if (sm_simulation_has_reduced_solver(sim))
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
// Adams' fixed-point iteration converges only for steps below about the inverse of the largest
// rate of the model's modes, its explicit stability limit: on a stiff model its steps run out or
// shrink to round-off where BDF steps over those modes. Its hints name the method first (raising
// max_steps alone pays for every step below that limit).
static const char* failure_hint(const sm_simulation* sim, int flag)
{
	const bool adams = sim->def.method == SM_METHOD_ADAMS;
	switch (flag) {
	case CV_TOO_MUCH_WORK:
		if (adams)
			return " (the max_steps internal steps allowed per advance were not enough: for a stiff model use "
			       "method bdf, as Adams keeps its steps below the stability limit of the fastest modes "
			       "(springmass modes), or raise max_steps (a model file's \"max_steps\", springmass run "
			       "--max-steps, an FMU's solver.max_steps))";
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
		if (adams)
			return " (the step size fell to round-off: for a stiff model use method bdf, which steps over the "
			       "fast modes Adams must follow; or the model moves faster than the tolerances can follow, or "
			       "its forces jump)";
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
	if (sim->need_restart && sm_simulation_has_reduced_solver(sim))
		sm_reduced_solver_invalidate(sim->linear_solver, false);
	if (sm_simulation_rhs(sm_simulation_cvode_time(sim, sim->time), sim->y, sim->y_saved, sim) != 0) {
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

// CVode in the C locale. CVODE writes its messages (kept by sm_simulation_error_handler for
// sm_simulation_last_error) with printf in the calling thread's locale: under a decimal comma a
// failure read "At t = 0.25 and h = 2,91762e-166" (the time, which the handler rewrites, came out
// with a point). In the C locale the step size reads as the library's own numbers do, in any
// locale (base.h).
static int cvode_in_c_locale(sm_simulation* sim, double tout, double* reached, int task)
{
	const sm_c_locale_scope scope = sm_enter_c_locale();
	const int flag = CVode(sim->cvode, tout, sim->y, reached, task);
	sm_leave_c_locale(scope);
	return flag;
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
		flag = check_step_size(sim, cvode_in_c_locale(sim, tout, reached, CV_ONE_STEP), reached);
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

// The rate of the inputs' jumps since the last advance [1/s]: the largest of their velocity
// measure (sim->jumps.rate) and the jumps of the inputs' and the dissipated power, summed over the
// inputs, over the work's and the dissipated energy's tolerances rtol |E| + atol (the energies
// integrate the sums: jumps that cancel leave them continuous, jumps within the tolerance each
// add up). Infinite where a sum is not a number.
static double input_jumps_rate(const sm_simulation* sim)
{
	const sm_input_jumps* j = &sim->jumps;
	if (isnan(j->input_power) || isnan(j->dissipated_power))
		return INFINITY;
	const double* atol = N_VGetArrayPointer(sim->tolerances);
	const double* y = N_VGetArrayPointer(sim->y);
	const double rtol = sim->def.relative_tolerance;
	const int64_t e = sm_simulation_dissipated_index(sim), w = sm_simulation_work_index(sim);
	const double rate = fmax(j->rate, fabs(j->input_power) / (rtol * fabs(y[w]) + atol[w]));
	return fmax(rate, fabs(j->dissipated_power) / (rtol * fabs(y[e]) + atol[e]));
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
	// Inputs that jumped since the last advance restart CVODE unless the history carries their
	// jumps over the interval: its length (or the largest step) times their rate at most 1.
	const double interval =
	    sim->def.max_step > 0.0 ? fmin(t_end - sim->time, sim->def.max_step) : t_end - sim->time;
	const double rate = input_jumps_rate(sim);
	if (rate > 0.0 && !(interval * rate <= 1.0))
		sim->need_restart = true;
	sim->jumps = (sm_input_jumps){0.0, 0.0, 0.0};
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
			flag = check_step_size(sim, cvode_in_c_locale(sim, cvode_end, &reached, CV_NORMAL), &reached);
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
			if (flag == CV_LSOLVE_FAIL && sm_simulation_has_reduced_solver(sim) &&
			    SUNLinSolLastFlag(sim->linear_solver) == SM_LS_MEM_FAIL)
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
				    now, end, failure_hint(sim, flag));
			if (usable)
				return sm_simulation_fail(sim, SM_ERROR_SOLVER,
				                          "CVODE failed with %s at t = %s s while advancing to %s s%s%s%s",
				                          failure_name(flag), now, end, failure_hint(sim, flag),
				                          sim->solver_message[0] ? ": " : "", sim->solver_message);
			// CVODE's last state is not finite: the message gives the time the simulation stays at.
			return sm_simulation_fail(
			    sim, SM_ERROR_SOLVER,
			    "CVODE failed with %s while advancing to %s s; the state it reached is not usable, so the "
			    "simulation stays at its last good state, t = %s s%s%s%s",
			    failure_name(flag), end, now, failure_hint(sim, flag), sim->solver_message[0] ? ": " : "",
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

// CVODE integrates the inputs' work less the driven particles' kinetic energy (simulation_callbacks.c),
// which is added here as their paths have it, before jump_work: where CVODE's part starts at minus
// that energy (sm_simulation_start_input_work) the two cancel to +0 exactly and the work reads
// jump_work itself, to the bit (-0 included).
double sm_simulation_input_work(const sm_simulation* sim)
{
	if (sim == NULL)
		return NAN;
	const double integrated = N_VGetArrayPointer(sim->y)[sm_simulation_work_index(sim)] +
	                          sm_simulation_driven_kinetic_energy(sim, sim->velocity);
	return integrated == 0.0 ? sim->jump_work : integrated + sim->jump_work;
}

double sm_simulation_input_power(sm_simulation* sim)
{
	if (sim == NULL)
		return NAN;
	const double* external = sm_simulation_external_forces(sim, sm_simulation_cvode_time(sim, sim->time));
	sm_model_forces(sim->model, sim->position, sim->velocity, external, sim->work_force);
	return sm_simulation_input_power_at(sim, sim->velocity, sim->work_force, external);
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

// m |v|^2 / 2 [J]
static double kinetic_energy(double m, const double* v)
{
	return 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// Whether a value given at a time t (16 units of round-off of the largest term) lies on the path
// value + change a call at t - dt set, where change is the sum of terms of which the largest is
// `term` in size: a caller's x0 + v t and the path's own x0 + v dt, summed over steps, part in the
// last bits; x0 + v0 t + a t^2 / 2 and x0 + t (v0 + t a / 2) part by round-off of v0 t and a t^2 / 2,
// however much of them cancels. A constant (change and term 0) within round-off is on its path too:
// a master that interpolates a held signal between two samples, w0 v + w1 v, is an ulp off at times.
// A path whose terms overflow at t holds no value given there (an infinite scale would take any):
// an old path kept over a new state at a far time may.
static bool on_path(double given, double value, double change, double term)
{
	const double path = value + change;
	const double scale = fmax(fmax(fabs(given), fabs(value)), fmax(fabs(change), term));
	return isfinite(scale) && fabs(given - path) <= 16.0 * DBL_EPSILON * scale;
}

// Whether a force given at time t continues the ramp (f0, r0) that started dt ago, whatever rate
// comes with it: within on_path's round-off, and beyond it by no more than the ramp moves in 16
// units of round-off of t (a caller's times and the ramp's start are rounded each: a ramp through
// samples every 1 ms is off by a few of them at 10 s where the force crosses 0). t = 0 allows
// on_path's round-off alone.
static bool force_continues(const double* f0, const double* r0, double dt, double t, const double* force)
{
	for (int c = 0; c < 3; c++)
		if (!on_path(force[c], f0[c], r0[c] * dt, fmax(fabs(r0[c] * dt), fabs(r0[c] * t))))
			return false;
	return true;
}

// The same for a drive (x0, v0, a0): the position and the velocity given continue its path.
static bool drive_continues(const double* x0, const double* v0, const double* a0, double dt, double t,
                            const double* position, const double* velocity)
{
	for (int c = 0; c < 3; c++) {
		const double a = a0[c];
		if (!on_path(velocity[c], v0[c], a * dt, fmax(fabs(a * dt), fabs(a * t))) ||
		    !on_path(
		        position[c], x0[c], dt * (v0[c] + 0.5 * dt * a),
		        fmax(fmax(fabs(v0[c] * dt), fabs(0.5 * dt * dt * a)), fabs(v0[c] * t) + fabs(a * dt * t))))
			return false;
	}
	return true;
}

// Whether a driven particle's position, velocity and acceleration given now lie on the path
// (x0, v0, a0) that started dt ago (on_path: however the caller summed it).
static bool on_driven_path(const double* x0, const double* v0, const double* a0, double dt,
                           const double* position, const double* velocity, const double* acceleration)
{
	for (int c = 0; c < 3; c++)
		if (acceleration[c] != a0[c])
			return false;
	return drive_continues(x0, v0, a0, dt, 0.0, position, velocity);
}

// Whether an external force and rate given now lie on the ramp (f0, r0) that started dt ago.
static bool on_force_ramp(const double* f0, const double* r0, double dt, const double* force,
                          const double* rate)
{
	for (int c = 0; c < 3; c++)
		if (rate[c] != r0[c])
			return false;
	return force_continues(f0, r0, dt, 0.0, force);
}

// The velocity change per second a free particle's external force given now makes against the
// value its ramp (started dt ago) has, |jump| / m, over the velocity's error tolerance
// rtol |v| + atol (per component, the largest) [1/s]: note_input_change. A force on a held
// particle moves nothing: 0.
static double force_jump_rate(const sm_simulation* sim, int32_t particle, double dt, const double* force)
{
	const int32_t k = sim->model->free_index[particle];
	if (k < 0)
		return 0.0;
	const size_t p = 3 * (size_t)particle;
	const double* atol = N_VGetArrayPointer(sim->tolerances) + sim->dofs + 3 * (size_t)k;
	double rate = 0.0;
	for (int c = 0; c < 3; c++) {
		const double jump = force[c] - (sim->external_force[p + c] + sim->force_rate[p + c] * dt);
		const double tolerance = sim->def.relative_tolerance * fabs(sim->velocity[p + c]) + atol[c];
		rate = fmax(rate, fabs(jump) / sim->model->mass[particle] / tolerance);
	}
	return isnan(rate) ? INFINITY : rate;
}

// What a drive's jump from the position and velocity it has now to those given leaves to CVODE's
// history (note_input_change): the largest velocity change per second the jump of its springs'
// forces makes at a free particle at their other ends, over that velocity's tolerance [1/s]; and
// the jumps of the energies' rates [W]: the inputs' power in the driven particle's own term
// -(m (g - alpha v) + load + its springs' forces) . v and in that of a driven particle at a
// spring's other end, and the power its springs' dampers and its mass damping dissipate. A jump
// of the driven particle reaches CVODE's state through these only (a velocity jump at an undamped
// spring through the powers alone: the driver's power jumps by the spring's force times it).
static sm_input_jumps drive_jumps(const sm_simulation* sim, int32_t particle, const double* position,
                                  const double* velocity)
{
	const sm_model* m = sim->model;
	const size_t p = 3 * (size_t)particle;
	const double *x0 = sim->position + p, *v0 = sim->velocity + p;
	const double* atol = N_VGetArrayPointer(sim->tolerances);
	const double rtol = sim->def.relative_tolerance;
	const double mass = m->mass[particle];
	double body_before[3], body_after[3];
	body_force(mass, m->def.gravity, m->def.mass_damping, v0, body_before);
	body_force(mass, m->def.gravity, m->def.mass_damping, velocity, body_after);
	double input_jump = 0.0;
	for (int c = 0; c < 3; c++) {
		const double load = m->load_count > 0 ? m->load[p + c] : 0.0;
		input_jump -= (body_after[c] + load) * velocity[c] - (body_before[c] + load) * v0[c];
	}
	double dissipation_jump = mass_damping_dissipation(mass, m->def.mass_damping, velocity) -
	                          mass_damping_dissipation(mass, m->def.mass_damping, v0);
	const int32_t* springs = sim->driven_springs + sim->driven_spring_start[particle];
	const int32_t count = sim->driven_spring_start[particle + 1] - sim->driven_spring_start[particle];
	double rate = 0.0;
	for (int32_t n = 0; n < count; n++) {
		const int32_t s = springs[n];
		const bool at_a = m->spring_a[s] == particle;
		const int32_t other = at_a ? m->spring_b[s] : m->spring_a[s];
		// The force on the other end, -f_a or f_a as it is b or a, before and after; the driven
		// particle feels its opposite.
		const size_t q = 3 * (size_t)other;
		const double *x = sim->position + q, *v = sim->velocity + q;
		double before[3], after[3];
		if (at_a) {
			dissipation_jump -= sm_model_spring_force(m, s, x0, x, v0, v, before);
			dissipation_jump += sm_model_spring_force(m, s, position, x, velocity, v, after);
			for (int c = 0; c < 3; c++) {
				before[c] = -before[c];
				after[c] = -after[c];
			}
		} else {
			dissipation_jump -= sm_model_spring_force(m, s, x, x0, v, v0, before);
			dissipation_jump += sm_model_spring_force(m, s, x, position, v, velocity, after);
		}
		const bool driven = m->motion[other] == SM_PARTICLE_DRIVEN;
		for (int c = 0; c < 3; c++) {
			input_jump += after[c] * velocity[c] - before[c] * v0[c];
			if (driven)
				input_jump -= (after[c] - before[c]) * v[c];
		}
		const int32_t k = m->free_index[other];
		if (k < 0)
			continue;
		for (int c = 0; c < 3; c++) {
			const double tolerance = rtol * fabs(v[c]) + atol[sim->dofs + 3 * (size_t)k + c];
			rate = fmax(rate, fabs(after[c] - before[c]) / m->mass[other] / tolerance);
		}
	}
	const sm_input_jumps jumps = {isnan(rate) ? INFINITY : rate, input_jump, dissipation_jump};
	return jumps;
}

// After an input changed at the current time: CVODE restarts here when the options ask for it
// and the right-hand side jumps, or when CVODE has stepped past (its steps assumed the input as it
// was). A restart starts BDF again at first order, which costs about rtol of the motion each
// time, so it is kept for jumps BDF's history cannot carry:
// - An input that turns (a new rate or acceleration from the value, and for a drive the velocity,
//   it had reached: `continuous`) leaves the right-hand side continuous, only its slope changes
//   (the inputs' work's too: what jumps in a driver's power is the rate of the driven particle's
//   kinetic energy, which CVODE does not integrate), and the history holds across such a kink
//   (within its error control, which rejects steps where the kink is sharp). A sine force ramped through
//   samples every 1 ms: 10 000 restarts over 10 s put the undamped oscillator of
//   tests/test_simulation_ramps.c 4.5e-3 m off, the history kept 5.4e-8 m.
// - A force that jumps by little (`jumps.rate`, the velocity change per second its jump makes over
//   the velocity's tolerance): the steps after a jump carry an error of about the step times the
//   jump's acceleration in the velocity, which the history keeps within the tolerance if the
//   advance's interval times the rate is at most 1; the advance decides. The same oscillator
//   under the samples held over each step (a jump at every call) ends 4.5e-3 m off with a restart
//   at each, 2.2e-6 m without. The power the force delivers jumps by jump . v, which
//   restarts nothing: held samples on a fast particle jump in it at every call, and a restart at
//   each costs the motion without sparing the inputs' work (a bob at up to 100 m/s under 0.01 N
//   sin(2 pi t) held over each 1 ms: kept, 4.2e-7 m and 3.1e-4 J off after 2 s; restarted where
//   the power's jump over the interval exceeded the work's tolerance, 1.4e-2 m and 2.9e-4 J).
// - A drive that jumps, by the same measure: its jump reaches CVODE's state only through its
//   springs' forces on the free particles at their other ends and through the energies' rates
//   (drive_jumps; an anchor of an undamped oscillator under 10 N set moving at 1e-3 m/s left
//   the inputs' work 2.2e-5 J off with the history kept, 5.8e-7 J restarted). The energies are
//   sums, so the power's jumps are summed over the drives that jump before they are measured
//   (sim->jumps; 200 such anchors each set moving at 5e-6 m/s, each jump within the tolerance,
//   left the work 1.3e-5 J off kept, 1.3e-6 J restarted). A base excitation
//   sampled every 1 ms jumps by much (its damper feels each new velocity): 9e-4 of the amplitude
//   off with the history kept, 2e-5 with restarts (tests/test_simulation.c); a motion port given
//   another FMU's position, velocity and acceleration at every 1 ms point (the coupled chain of
//   the README) leaves its path by little: 2 restarts in 2000 points, 7.5e-6 m from the monolithic
//   chain, 4.8e-4 m with a restart at each.
static void note_input_change(sm_simulation* sim, bool continuous, sm_input_jumps jumps)
{
	sim->input_jumped = true;
	sim->input_changed = true;
	if (cvode_ahead(sim)) {
		sim->need_restart = true;
	} else if (sim->def.restart_on_input_change && !continuous) {
		sim->jumps.rate = fmax(sim->jumps.rate, jumps.rate);
		sim->jumps.input_power += jumps.input_power;
		sim->jumps.dissipated_power += jumps.dissipated_power;
	}
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
	const double dt = sim->time - sim->drive_time[particle];
	if (on_driven_path(sim->drive_position + p, sim->drive_velocity + p, sim->drive_acceleration + p, dt,
	                   position, velocity, acceleration))
		return SM_OK;
	// The position and velocity where the path has them, a new acceleration: the path turns. The
	// driver's power jumps by m (a - a0) . v, but only in the part that changes the particle's
	// kinetic energy, which CVODE does not integrate (sm_simulation_driving_power_at).
	const bool turns = drive_continues(sim->drive_position + p, sim->drive_velocity + p,
	                                   sim->drive_acceleration + p, dt, sim->time, position, velocity);
	const sm_input_jumps jumps =
	    turns ? (sm_input_jumps){0.0, 0.0, 0.0} : drive_jumps(sim, particle, position, velocity);
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
	// takes in the jump; the part that is its kinetic energy the inputs' work takes from its path
	// (sm_simulation_input_work). An energy beyond a double is not handed on to the inputs' work.
	const int32_t* springs = sim->driven_springs + sim->driven_spring_start[particle];
	const int32_t count = sim->driven_spring_start[particle + 1] - sim->driven_spring_start[particle];
	const double before =
	    sm_model_particle_energy(sim->model, sim->position, sim->velocity, particle, springs, count) -
	    kinetic_energy(sim->model->mass[particle], sim->velocity + p);
	memcpy(sim->drive_position + p, back ? origin.value : position, 3 * sizeof(double));
	memcpy(sim->drive_velocity + p, back ? origin.rate : velocity, 3 * sizeof(double));
	memcpy(sim->drive_acceleration + p, back ? origin.acceleration : acceleration, 3 * sizeof(double));
	sim->drive_time[particle] = back ? origin.time : sim->time;
	const bool undone = back && sm_input_origins_settle(sim, particle);
	if (!undone)
		note_input_change(sim, turns, jumps);
	// Only this particle's position and velocity change: written as sm_simulation_refresh_outputs
	// writes them, which every call that moves the state or the time has done for the rest, so that
	// a call costs the same whatever the model's size (a host drives many ports at every step).
	driven_state(sim, particle, sm_simulation_cvode_time(sim, sim->time), sim->position + p,
	             sim->velocity + p);
	const double work =
	    sm_model_particle_energy(sim->model, sim->position, sim->velocity, particle, springs, count) -
	    kinetic_energy(sim->model->mass[particle], sim->velocity + p) - before;
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
	const double dt = sim->time - sim->force_time[particle];
	if (on_force_ramp(f, r, dt, force, rate))
		return SM_OK;
	const bool turns = force_continues(f, r, dt, sim->time, force);  // the force the ramp has, a new rate
	const sm_input_jumps jumps = {turns ? 0.0 : force_jump_rate(sim, particle, dt, force), 0.0, 0.0};
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
		note_input_change(sim, turns, jumps);
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
	sm_input_origins_span(sim);  // the restart it asks for stays, whatever the inputs do
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

// The inputs' work `work` [J] as it was before a new time or new masses, which change the driven
// particles' kinetic energy that sm_simulation_input_work adds: started again from it (CVODE
// restarts there). A work beyond a double is left as it reads.
static void keep_input_work(sm_simulation* sim, double work)
{
	if (isfinite(work))
		sm_simulation_start_input_work(sim, work);
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
	sm_simulation_pack(sim, x, v, N_VGetArrayPointer(sim->y));
	sm_input_origins_span(sim);  // the restart it asks for stays; inputs set back take their paths
	const double work = sm_simulation_input_work(sim);
	sim->time = time;
	// CVODE restarts here, at 0 on its axis: the outputs are those of the restart already, not of
	// an axis of the past (a driven particle's position would part from the run's in its last bit).
	sim->time_origin = time;
	sim->need_restart = true;
	sm_simulation_refresh_outputs(sim);
	keep_input_work(sim, work);
	return SM_OK;
}

sm_status sm_simulation_reset(sm_simulation* sim)
{
	if (sim == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sm_simulation_restore_springs(sim);
	sm_simulation_load_initial_state(sim);
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
	const double work = sm_simulation_input_work(sim);  // with the old masses
	sm_model* previous = sim->model;
	sim->model = copy;
	sim->solver_message[0] = '\0';
	sm_status st = sm_simulation_build_events(sim);
	const char* failure = st == SM_ERROR_OUT_OF_MEMORY ? "update_model: out of memory for the break events"
	                                                   : "update_model: cannot set up the break events";
	if (st == SM_OK && sm_simulation_has_reduced_solver(sim) &&
	    !sm_reduced_solver_rebuild(sim->linear_solver)) {
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
	sm_simulation_refresh_masses(sim);
	sim->need_restart = true;
	sm_input_origins_span(sim);  // the restart it asks for stays; inputs set back take their paths
	sm_simulation_refresh_outputs(sim);
	keep_input_work(sim, work);
	return SM_OK;
}

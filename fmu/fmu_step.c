// springmass FMU: fmi2DoStep, which advances the simulation over a communication step, and the
// status functions (fmi2CancelStep, fmi2GetStatus and its siblings).
#include "fmu_instance.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

// ---------------------------------------------------------------------------------------------
// FMI 2.0 Co-Simulation: stepping and status
// ---------------------------------------------------------------------------------------------

// Whether every output is finite, checked over a superset of their values: every particle's
// position and velocity, where there are motion ports (whose force outputs are the forces the
// model exerts on their particles) the forces on every particle, and the energies. False only
// sends end_step on to read each output, to name the first that is not finite. Reading each
// through the table at every step took half of a communication step that CVODE interpolates (the
// bundled two-mass chain at 1e-4 s with a stop time: 2500 of 5300 instructions, for 20 outputs
// among 62 variables); the check takes 980, 700 of them the forces and the energies.
static bool outputs_finite(instance* inst)
{
	const size_t n3 = 3 * (size_t)inst->particle_count;
	const double* x = sm_simulation_positions(inst->sim);
	const double* u = sm_simulation_velocities(inst->sim);
	bool motion_ports = false;
	for (int32_t p = 0; p < inst->port_count; ++p)
		motion_ports = motion_ports || inst->ports[p].kind == SM_PORT_MOTION;
	const double* f = motion_ports ? fmu_current_forces(inst) : NULL;
	// 0 x is 0 for a finite x and NaN for an infinite or NaN one.
	double zero = 0.0;
	for (size_t i = 0; i < n3; ++i)
		zero += 0.0 * x[i] + 0.0 * u[i] + (f ? 0.0 * f[i] : 0.0);
	const sm_energies* e = fmu_current_energies(inst);
	return zero == 0.0 && isfinite(e->kinetic) && isfinite(e->elastic) && isfinite(e->gravity) &&
	       isfinite(fmu_dissipated_energy(inst)) && isfinite(fmu_input_work(inst));
}

// Ends a step from t that reached t_end. A finite state whose outputs overflow a double (the
// energies of 1e218 kg at 1e98 m above the origin; the force on a driven particle, which no state
// of the integration holds) cannot be reported: the step is then discarded at its end, like one
// the solver could not take beyond a time it reached, and that end is the last successful time,
// where the state and the outputs are.
static fmi2Status end_step(instance* inst, double t, double t_end)
{
	inst->time = t_end;
	inst->last_successful_time = t_end;
	const char* overflowing = NULL;
	if (outputs_finite(inst))
		return fmi2OK;
	for (int32_t i = 0; i < inst->table.count && overflowing == NULL; ++i) {
		const fmu_variable* v = &inst->table.variables[i];
		if (v->type == FMU_REAL && v->causality == FMU_OUTPUT && !isfinite(fmu_real_value(inst, v)))
			overflowing = v->name;
	}
	if (overflowing != NULL) {
		inst->state = ST_STEP_FAILED;
		fmu_logf(
		    inst, fmi2Discard, LOG_DISCARD,
		    "fmi2DoStep: the step from %s reached %s, where the output %s overflows a double; the state and "
		    "outputs are at %s, fmi2LastSuccessfulTime",
		    fmu_number_text(t).text, fmu_number_text(t_end).text, overflowing, fmu_number_text(t_end).text);
		return fmi2Discard;
	}
	return fmi2OK;
}

// Logs why a step from t to t_end stopped at the FMU's time, where the state and the outputs are,
// and how the master goes on: the instance is in the step-failed state, where fmi2DoStep is
// refused. The simulation's report (st) is written for its own callers: its times run on the
// simulation's clock, t - start (CVODE's own text's too), and after
// its step limit it says that the next advance goes on. So a step limit is told here in the FMU's
// words, and any other report comes with its clock named.
static void log_discard(instance* inst, sm_status st, double t, double t_end)
{
	char reason[SM_ERROR_MESSAGE_CAPACITY + 128];
	// Adams keeps its steps below the stability limit of the model's fastest modes: on a stiff
	// model the cure is the method (simulation.c's hints say the same).
	if (st == SM_ERROR_STEP_LIMIT && inst->solver.method == SM_METHOD_ADAMS)
		snprintf(reason, sizeof reason,
		         "CVODE used the %d internal steps solver.max_steps allows a communication step (for a stiff "
		         "model set solver.method bdf, as Adams keeps its steps below the stability limit of the "
		         "fastest modes, or a larger solver.max_steps, before fmi2ExitInitializationMode)",
		         (int)inst->solver.max_steps);
	else if (st == SM_ERROR_STEP_LIMIT)
		snprintf(reason, sizeof reason,
		         "CVODE used the %d internal steps solver.max_steps allows a communication step (set a "
		         "larger solver.max_steps before fmi2ExitInitializationMode, or look for a spring much "
		         "stiffer than the others or a huge force)",
		         (int)inst->solver.max_steps);
	else
		snprintf(reason, sizeof reason, "The solver's report (its times count from the start time %s s): %s",
		         fmu_number_text(inst->start_time).text, sm_simulation_last_error(inst->sim));
	fmu_logf(
	    inst, fmi2Discard, LOG_DISCARD,
	    "fmi2DoStep: the step from %s to %s stopped at %s (readable as fmi2LastSuccessfulTime), where the "
	    "state and outputs are; restore a state saved before (fmi2SetFMUstate), reset or terminate. %s",
	    fmu_number_text(t).text, fmu_number_text(t_end).text, fmu_number_text(inst->time).text, reason);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
	instance* inst = c;
	(void)noSetFMUStatePriorToCurrentPoint;
	if (!fmu_allowed(inst, "fmi2DoStep", ST_STEP_COMPLETE))
		return fmi2Error;
	double t = currentCommunicationPoint, h = communicationStepSize;
	if (!isfinite(t) || !isfinite(h) || !(h > 0.0)) {
		log_error(inst, "fmi2DoStep: communication step size %g at t = %g must be finite and > 0", h, t);
		return fmi2Error;
	}
	double tolerance = 1e3 * DBL_EPSILON * fmax(1.0, fabs(inst->time));
	if (fabs(t - inst->time) > tolerance) {
		log_error(inst, "fmi2DoStep: communication point %s does not match the FMU's time %s",
		          fmu_number_text(t).text, fmu_number_text(inst->time).text);
		return fmi2Error;
	}
	double t_end = t + h;
	if (!isfinite(t_end) || !isfinite(t_end - inst->start_time)) {
		log_error(inst, "fmi2DoStep: the step from %g by %g s ends beyond the largest representable time", t,
		          h);
		return fmi2Error;
	}
	// The stop time is resolved like the communication point, 1000 ulps of max(1 s, |stop|), on
	// either side of zero. Checked before the steps below the time resolution too: each moves the
	// FMU's time on, and a run of them would otherwise carry it past the stop time unchecked.
	if (inst->stop_time_defined &&
	    t_end > inst->stop_time + 1e3 * DBL_EPSILON * fmax(1.0, fabs(inst->stop_time))) {
		log_error(inst, "fmi2DoStep: step to %s goes past the stop time %s set in fmi2SetupExperiment",
		          fmu_number_text(t_end).text, fmu_number_text(inst->stop_time).text);
		return fmi2Error;
	}
	// The simulation's time is t - start (start: the start time of its initial state), resolved to
	// 4 eps max(1 s, |t - start|); the step it sees is the difference of the ends as they round,
	// so that it moves with the master's clock. At t = 1.7e9 s (a Unix time) and start 1.7e9 s, a
	// step of 1e-6 s is 4 ulps of t, 9.5e-7 s, and that is integrated. A step the simulation's
	// time does not resolve is
	// - below the resolution of the master's clock, 4 eps max(1 s, |t|): that clock catching up
	//   with round-off (t + h summed over steps lands an ulp short of its stop time, and the rest
	//   is stepped). FMI 2.0 (4.2.2) asks only h > 0 of it: the inputs are taken, as in any step,
	//   and the FMU's time moves to t + h with the state at t (it would move by h |v|);
	// - otherwise refused: the master's clock resolves it but the simulation's time, far larger
	//   (a state's start time is its own), does not, and every step of that size would leave the
	//   state where it is.
	// A point taken within its tolerance may trail the FMU's time: a step that ends there or before
	// has nothing to integrate either.
	const double simulation_step = (t_end - inst->start_time) - (t - inst->start_time);
	const double resolution = 4.0 * DBL_EPSILON * fmax(1.0, fabs(t - inst->start_time));
	const double clock_resolution = 4.0 * DBL_EPSILON * fmax(1.0, fabs(t));
	if (!(simulation_step >= resolution && t_end > inst->time) && h < clock_resolution) {
		if (fmu_apply_inputs(inst, "fmi2DoStep") != fmi2OK)
			return fmi2Error;
		if (fmu_logging(inst, LOG_SOLVER))
			fmu_logf(inst, fmi2OK, LOG_SOLVER,
			         "step %s -> %s: below the time resolution %s s, nothing to integrate; the time moves on",
			         fmu_number_text(t).text, fmu_number_text(t_end).text, fmu_number_text(resolution).text);
		return end_step(inst, t, fmax(inst->time, t_end));
	}
	if (!(simulation_step >= resolution)) {
		log_error(inst,
		          "fmi2DoStep: communication step size %g at t = %g is below the time resolution %g s of the "
		          "simulation's time t - start = %g",
		          h, t, resolution, t - inst->start_time);
		return fmi2Error;
	}
	// A point taken within its tolerance may lag the FMU's time by more than a short step.
	if (!(t_end > inst->time)) {
		log_error(inst, "fmi2DoStep: the step from %s by %s s ends at %s, not after the FMU's time %s",
		          fmu_number_text(t).text, fmu_number_text(h).text, fmu_number_text(t_end).text,
		          fmu_number_text(inst->time).text);
		return fmi2Error;
	}
	if (fmu_apply_inputs(inst, "fmi2DoStep") != fmi2OK)
		return fmi2Error;
	// The solver's counters for the log only: reading them costs a fifteenth of a step that CVODE
	// interpolates.
	const bool log_solver = fmu_logging(inst, LOG_SOLVER);
	const sm_statistics before = log_solver ? sm_simulation_statistics(inst->sim) : (sm_statistics){0};
	// Up to a stop time the master gave, CVODE steps on past the communication point and the
	// outputs are interpolated from its steps: a changed input, a restored state or a tunable
	// parameter restarts it at the point, so steps past it never see inputs they should not.
	const double t_stop = inst->stop_time_defined ? fmax(inst->stop_time, t_end) : t_end;
	sm_status st =
	    sm_simulation_advance_interpolated(inst->sim, t_end - inst->start_time, t_stop - inst->start_time);
	fmu_forget_derived_values(inst);

	int32_t breaks = sm_simulation_break_count(inst->sim);
	for (; inst->breaks_logged < breaks; ++inst->breaks_logged) {
		sm_break_event e = sm_simulation_break(inst->sim, inst->breaks_logged);
		sm_spring_def s;
		sm_model_get_spring(sm_simulation_model(inst->sim), e.spring, &s);
		// A particle without a name by its index, as the variables' descriptions name it.
		const char* a = sm_document_particle_name(inst->doc, s.a);
		const char* b = sm_document_particle_name(inst->doc, s.b);
		char a_label[32], b_label[32];
		snprintf(a_label, sizeof a_label, "particle %d", (int)s.a);
		snprintf(b_label, sizeof b_label, "particle %d", (int)s.b);
		if (fmu_logging(inst, LOG_EVENTS))
			fmu_logf(inst, fmi2OK, LOG_EVENTS, "t = %s: spring %d between %s and %s broke",
			         fmu_number_text(e.time + inst->start_time).text, (int)e.spring, a ? a : a_label,
			         b ? b : b_label);
	}
	if (log_solver) {
		const sm_statistics after = sm_simulation_statistics(inst->sim);
		fmu_logf(inst, fmi2OK, LOG_SOLVER,
		         "step %s -> %s: %lld internal steps, %lld right-hand sides, %lld Jacobians, %lld restarts, "
		         "%lld error-test and %lld convergence failures",
		         fmu_number_text(t).text, fmu_number_text(t_end).text,
		         (long long)(after.steps - before.steps),
		         (long long)(after.rhs_evaluations - before.rhs_evaluations),
		         (long long)(after.jacobian_evaluations - before.jacobian_evaluations),
		         (long long)(after.restarts - before.restarts),
		         (long long)(after.error_test_failures - before.error_test_failures),
		         (long long)(after.convergence_failures - before.convergence_failures));
	}
	if (st != SM_OK) {
		inst->time = inst->start_time + sm_simulation_time(inst->sim);
		inst->last_successful_time = inst->time;
		inst->state = ST_STEP_FAILED;
		log_discard(inst, st, t, t_end);
		return fmi2Discard;
	}
	return end_step(inst, t, t_end);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2CancelStep", ST_STEP_COMPLETE | ST_STEP_FAILED))
		return fmi2Error;
	log_error(inst, "fmi2CancelStep: fmi2DoStep is synchronous and never returns fmi2Pending");
	return fmi2Error;
}

static bool check_status_value(instance* inst, const char* function, const void* value)
{
	if (!value)
		log_error(inst, "%s: NULL value", function);
	return value != NULL;
}

// Refuses a status kind that `function` does not deliver. FMI 2.0 (4.2.3): "If a status is required
// which cannot be retrieved by the slave it returns fmi2Discard" (2.1.3 lists the fmi2Get*Status
// functions among those that may discard): a kind of fmi2StatusKind that is not this function's,
// such as fmi2GetRealStatus(fmi2DoStepStatus) or any kind of fmi2GetIntegerStatus, is discarded,
// logged as such. A value outside fmi2StatusKind asks for no status at all: an fmi2Error.
static fmi2Status status_not_provided(instance* inst, const char* function, fmi2StatusKind s)
{
	static const char* const kinds[4][2] = {{"fmi2DoStepStatus", "fmi2GetStatus"},
	                                        {"fmi2PendingStatus", "fmi2GetStringStatus"},
	                                        {"fmi2LastSuccessfulTime", "fmi2GetRealStatus"},
	                                        {"fmi2Terminated", "fmi2GetBooleanStatus"}};
	const int k = (int)s;
	if (k < 0 || k >= 4) {
		log_error(inst, "%s: status kind %d is not an fmi2StatusKind (0 to 3)", function, k);
		return fmi2Error;
	}
	fmu_logf(inst, fmi2Discard, LOG_DISCARD, "%s: status kind %d (%s) is not delivered here: read it with %s",
	         function, k, kinds[k][0], kinds[k][1]);
	return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED) ||
	    !check_status_value(inst, "fmi2GetStatus", value))
		return fmi2Error;
	if (s == fmi2DoStepStatus) {
		*value = inst->state == ST_STEP_FAILED ? fmi2Discard : fmi2OK;
		return fmi2OK;
	}
	return status_not_provided(inst, "fmi2GetStatus", s);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetRealStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED) ||
	    !check_status_value(inst, "fmi2GetRealStatus", value))
		return fmi2Error;
	if (s == fmi2LastSuccessfulTime) {
		*value = inst->last_successful_time;
		return fmi2OK;
	}
	return status_not_provided(inst, "fmi2GetRealStatus", s);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetIntegerStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED) ||
	    !check_status_value(inst, "fmi2GetIntegerStatus", value))
		return fmi2Error;
	return status_not_provided(inst, "fmi2GetIntegerStatus", s);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetBooleanStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED) ||
	    !check_status_value(inst, "fmi2GetBooleanStatus", value))
		return fmi2Error;
	// After a discarded step the instance cannot step on from where it stopped (fmi2DoStep is
	// refused in the step-failed state): it asks a master that cannot restore a saved state to
	// end the simulation at fmi2LastSuccessfulTime (fmpy's simulate_fmu then returns the results
	// up to there), rather than try a step that fails. Otherwise the model never asks to stop.
	if (s == fmi2Terminated) {
		*value = inst->state == ST_STEP_FAILED ? fmi2True : fmi2False;
		return fmi2OK;
	}
	return status_not_provided(inst, "fmi2GetBooleanStatus", s);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetStringStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED) ||
	    !check_status_value(inst, "fmi2GetStringStatus", value))
		return fmi2Error;
	if (s == fmi2PendingStatus) {
		*value = "";
		return fmi2OK;
	}
	return status_not_provided(inst, "fmi2GetStringStatus", s);
}

// springmass FMU: derivatives. fmi2GetDirectionalDerivative (outputs with respect to inputs at
// the communication point, from the analytic Jacobian), fmi2SetRealInputDerivatives (inputs that
// change linearly over the coming steps) and fmi2GetRealOutputDerivatives (first time derivatives
// of the outputs).
#include "fmu_instance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// FMI 2.0: directional derivatives of outputs with respect to inputs at the current
// communication point (the direct feed-through a master needs). With dx and dv the seeds of the
// motion ports' prescribed positions and velocities and g the seeds of the force inputs:
//   d(force on a driven particle)  = (df/dx dx + df/dv dv)_p + g_p   (analytic Jacobian product;
//                                    g_p = 0, as no force port is at a motion port's particle)
//   d(kinetic energy)              = sum m_i v_i . dv_i
//   d(gravitational energy)        = -sum (m_i g + F_i) . dx_i (F_i the particle's load)
//   d(elastic energy)              = -sum f_el,i . dx_i with f_el = f(x, 0) - m g - F (the forces
//                                    at zero velocity are elastic plus weight and load only)
//   d(position, velocity of a particle) = dx_i, dv_i: a driven particle is where its port puts it
//   d(inputs' work)                = the sum of the three energies' (a motion set elsewhere does
//                                    the work of the energy it adds at once); 0 in initialisation
//                                    mode, where the inputs give the initial state and do no work
// Positions and velocities of free particles and the dissipated energy are states: their
// derivatives with respect to the current inputs are zero (dx and dv are zero there).
// ---------------------------------------------------------------------------------------------

// The change of an output that is a function of the state (the force on a driven particle, the
// kinetic, elastic and gravitational energies, their sum for the inputs' work) along a change
// (dx, dv) of every particle's position
// and velocity, at the current state: the Jacobian product's row of the driven particle, sum m v.dv,
// -sum f_elastic.dx (f_elastic = f(x, 0) - m g - F, the springs' forces without damping) and
// -sum (m g + F).dx (F the loads). With an input's seed as (dx, dv) it is a directional derivative, with the
// velocities and accelerations a time derivative. work holds 3 n3 doubles; *evaluated says which of its parts
// hold values of earlier calls for the same (dx, dv) (bit 0: the Jacobian product, bit 1: f_elastic).
static double state_output_change(const instance* inst, const fmu_variable* v, const double* dx,
                                  const double* dv, double* work, unsigned* evaluated)
{
	const size_t n3 = 3 * (size_t)inst->particle_count;
	const sm_model* model = sm_simulation_model(inst->sim);
	const double* x = sm_simulation_positions(inst->sim);
	const double* u = sm_simulation_velocities(inst->sim);
	double* df = work;
	double* elastic = work + n3;
	double* zero = work + 2 * n3;
	if (v->source == FMU_SRC_PORT_FORCE) {
		if (!(*evaluated & 1u)) {
			sm_model_jacobian_product(model, x, u, SM_JACOBIAN_EXACT, dx, dv, df);
			*evaluated |= 1u;
		}
		return df[3 * (size_t)inst->ports[v->index].particle + (size_t)v->component];
	}
	// A motion input set elsewhere moves its particle at once: the inputs' work changes by the
	// energy that adds, the sum of the three.
	const bool all = v->source == FMU_SRC_ENERGY_INPUT;
	if ((all || v->source == FMU_SRC_ENERGY_ELASTIC) && !(*evaluated & 2u)) {
		memset(zero, 0, n3 * sizeof(double));
		sm_model_forces(model, x, zero, NULL, elastic);
		*evaluated |= 2u;
	}
	const sm_model_def def = sm_model_get_def(model);
	double change = 0.0;
	for (int32_t p = 0; p < inst->particle_count; ++p) {
		sm_particle_def pd;
		sm_model_get_particle(model, p, &pd);
		for (size_t c3 = 0; c3 < 3; ++c3) {
			const size_t i = 3 * (size_t)p + c3;
			if (all || v->source == FMU_SRC_ENERGY_KINETIC)
				change += pd.mass * u[i] * dv[i];
			// The constant forces, gravity and the load: the gravitational energy's gradient is minus
			// them, and the elastic energy's minus the rest of the forces at zero velocities.
			const double constant = pd.mass * def.gravity[c3] + pd.load[c3];
			if (all || v->source == FMU_SRC_ENERGY_GRAVITY)
				change -= constant * dx[i];
			if (all || v->source == FMU_SRC_ENERGY_ELASTIC)
				change -= (elastic[i] - constant) * dx[i];
		}
	}
	return change;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
	instance* inst = c;
	const char* fn = "fmi2GetDirectionalDerivative";
	// Where values can be read (FMI 2.0, 4.2.4), the error state included, as for fmi2GetReal.
	if (!fmu_allowed(inst, fn, ST_RUNNING))
		return fmi2Error;
	if ((nUnknown > 0 && (!vUnknown_ref || !dvUnknown)) || (nKnown > 0 && (!vKnown_ref || !dvKnown))) {
		log_error(inst, "%s: NULL array", fn);
		return fmi2Error;
	}
	size_t n3 = 3 * (size_t)inst->particle_count;
	double* dx = inst->scratch;
	double* dv = dx + n3;
	double* work = dv + n3;
	memset(dx, 0, 2 * n3 * sizeof(double));
	for (size_t k = 0; k < nKnown; ++k) {
		if (vKnown_ref[k] >= (fmi2ValueReference)inst->table.count) {
			log_error(inst, "%s: unknown value reference %u", fn, (unsigned)vKnown_ref[k]);
			return fmi2Error;
		}
		const fmu_variable* v = &inst->table.variables[vKnown_ref[k]];
		if (v->causality != FMU_INPUT) {
			log_error(inst, "%s: known %s is not an input", fn, v->name);
			return fmi2Error;
		}
		if (!isfinite(dvKnown[k])) {
			log_error(inst, "%s: seed of %s is not finite", fn, v->name);
			return fmi2Error;
		}
	}
	for (size_t k = 0; k < nUnknown; ++k) {
		if (vUnknown_ref[k] >= (fmi2ValueReference)inst->table.count) {
			log_error(inst, "%s: unknown value reference %u", fn, (unsigned)vUnknown_ref[k]);
			return fmi2Error;
		}
		const fmu_variable* v = &inst->table.variables[vUnknown_ref[k]];
		if (v->causality != FMU_OUTPUT && v->causality != FMU_LOCAL) {
			log_error(inst, "%s: unknown %s is not an output", fn, v->name);
			return fmi2Error;
		}
	}
	if ((!inst->sim || inst->sim_dirty) ? fmu_ensure_simulation(inst, fn) != fmi2OK
	                                    : fmu_apply_inputs(inst, fn) != fmi2OK)
		return fmi2Error;
	for (size_t k = 0; k < nKnown; ++k) {
		const fmu_variable* v = &inst->table.variables[vKnown_ref[k]];
		size_t i = 3 * (size_t)inst->ports[v->index].particle + (size_t)v->component;
		if (v->source == FMU_SRC_PORT_POSITION)
			dx[i] += dvKnown[k];
		else if (v->source == FMU_SRC_PORT_VELOCITY)
			dv[i] += dvKnown[k];
	}
	unsigned evaluated = 0;
	for (size_t k = 0; k < nUnknown; ++k) {
		const fmu_variable* v = &inst->table.variables[vUnknown_ref[k]];
		double result = 0.0;
		if (v->source == FMU_SRC_PORT_FORCE) {
			// g_p is 0: no force port shares a motion port's particle (the model file lets only
			// probes share one). Looking for one went over every known for every unknown.
			result = state_output_change(inst, v, dx, dv, work, &evaluated);
		} else if (v->source == FMU_SRC_PARTICLE_POSITION || v->source == FMU_SRC_PARTICLE_VELOCITY) {
			const size_t i = 3 * (size_t)v->index + (size_t)v->component;
			result = v->source == FMU_SRC_PARTICLE_POSITION ? dx[i] : dv[i];
		} else if (v->source == FMU_SRC_ENERGY_KINETIC || v->source == FMU_SRC_ENERGY_GRAVITY ||
		           v->source == FMU_SRC_ENERGY_ELASTIC ||
		           (v->source == FMU_SRC_ENERGY_INPUT && inst->state != ST_INITIALIZATION)) {
			result = state_output_change(inst, v, dx, dv, work, &evaluated);
		}
		dvUnknown[k] = result;
	}
	return fmi2OK;
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0 Co-Simulation: derivatives of the inputs and of the outputs
// ---------------------------------------------------------------------------------------------

// Input derivatives (canInterpolateInputs): over the coming steps a force port pushes with
// P.fx + d(P.fx)/dt (t - t_n), a motion port moves along P.x + P.vx s + d(P.vx)/dt s^2 / 2 with
// velocity P.vx + d(P.vx)/dt s (s = t - t_n), from the communication point t_n at which its inputs
// or their derivatives were last set; a derivative holds until set again, fmi2Reset clears it. A
// motion port's position moves with its velocity input, so the derivative of P.x is taken but not
// used, as are orders above 1, of which the extrapolation uses none (both logged as events).
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
	instance* inst = c;
	const char* fn = "fmi2SetRealInputDerivatives";
	if (!fmu_allowed(inst, fn, ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !fmu_check_arrays(inst, fn, vr, nvr, value) || !fmu_check_arrays(inst, fn, vr, nvr, order))
		return fmi2Error;
	for (size_t k = 0; k < nvr; ++k) {
		const fmu_variable* v = fmu_lookup(inst, fn, vr[k], FMU_REAL);
		if (!v)
			return fmi2Error;
		if (v->causality != FMU_INPUT) {
			log_error(inst, "%s: %s is not an input", fn, v->name);
			return fmi2Error;
		}
		if (order[k] < 1) {
			log_error(inst, "%s: order %d of %s: the orders of derivatives start at 1", fn, (int)order[k],
			          v->name);
			return fmi2Error;
		}
		if (!isfinite(value[k])) {
			log_error(inst, "%s: the derivative of %s must be finite, not %s", fn, v->name,
			          fmu_number_text(value[k]).text);
			return fmi2Error;
		}
	}
	for (size_t k = 0; k < nvr; ++k) {
		const fmu_variable* v = &inst->table.variables[vr[k]];
		port_values* h = &inst->held[v->index];
		if (order[k] > 1 || v->source == FMU_SRC_PORT_POSITION) {
			fmu_logf(inst, fmi2OK, LOG_EVENTS, "%s: order %d of %s is not used (%s)", fn, (int)order[k],
			         v->name,
			         order[k] > 1 ? "inputs are extrapolated with their first derivatives"
			                      : "a motion port's position moves with its velocity input");
			continue;
		}
		*(v->source == FMU_SRC_PORT_VELOCITY ? &h->acceleration[v->component]
		                                     : &h->force_rate[v->component]) = value[k];
		inst->port_dirty[v->index] = true;
	}
	return fmi2OK;
}

// First time derivatives of outputs (maxOutputDerivativeOrder = 1) at the current state and
// inputs, from the equations of motion: a position's is the velocity; a velocity's the
// acceleration a = f / m of a free particle (0 for a held one; a motion port's particle has the
// acceleration its velocity input's derivative gives, 0 unless set); a driven particle's force and the
// kinetic, elastic and gravitational energies change along (v, a) as state_output_change gives; the
// dissipated energy's is the dissipated power, the rate the simulation integrates it at, and the
// inputs' work's the power they deliver (sm_simulation_input_power).
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
	instance* inst = c;
	const char* fn = "fmi2GetRealOutputDerivatives";
	if (!fmu_allowed(inst, fn, ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED | ST_ERROR))
		return fmi2Error;
	if (nvr == 0)
		return fmi2OK;
	if (!vr || !order || !value) {
		log_error(inst, "%s: NULL array", fn);
		return fmi2Error;
	}
	for (size_t k = 0; k < nvr; ++k) {
		const fmu_variable* v = fmu_lookup(inst, fn, vr[k], FMU_REAL);
		if (!v)
			return fmi2Error;
		if (v->causality != FMU_OUTPUT) {
			log_error(inst, "%s: %s is not an output", fn, v->name);
			return fmi2Error;
		}
		if (order[k] != 1) {
			log_error(inst,
			          "%s: order %d of %s: this FMU gives first derivatives (maxOutputDerivativeOrder = 1)",
			          fn, (int)order[k], v->name);
			return fmi2Error;
		}
	}
	if (fmu_ensure_simulation(inst, fn) != fmi2OK)
		return fmi2Error;
	const size_t n3 = 3 * (size_t)inst->particle_count;
	const sm_model* model = sm_simulation_model(inst->sim);
	const double* x = sm_simulation_positions(inst->sim);
	const double* u = sm_simulation_velocities(inst->sim);
	double* a = inst->scratch;
	double* work = a + n3;
	// The accelerations need the forces: only a velocity's derivative and the state outputs' use
	// them, not a position's (a velocity) or the energies the simulation integrates.
	bool accelerations = false;
	for (size_t k = 0; k < nvr && !accelerations; ++k) {
		const fmu_source source = inst->table.variables[vr[k]].source;
		accelerations = source != FMU_SRC_PORT_POSITION && source != FMU_SRC_ENERGY_DISSIPATED &&
		                source != FMU_SRC_ENERGY_INPUT;
	}
	if (accelerations) {
		const double* f = fmu_current_forces(inst);
		for (int32_t p = 0; p < inst->particle_count; ++p) {
			sm_particle_def pd;
			sm_model_get_particle(model, p, &pd);
			for (size_t c3 = 0; c3 < 3; ++c3) {
				const size_t i = 3 * (size_t)p + c3;
				a[i] = pd.motion == SM_PARTICLE_FREE ? f[i] / pd.mass : 0.0;
			}
		}
		for (int32_t p = 0; p < inst->port_count; ++p)
			if (inst->ports[p].kind == SM_PORT_MOTION)
				memcpy(a + 3 * (size_t)inst->ports[p].particle, inst->held[p].acceleration,
				       3 * sizeof(double));
	}
	unsigned evaluated = 0;
	const fmu_variable* overflowing = NULL;
	for (size_t k = 0; k < nvr; ++k) {
		const fmu_variable* v = &inst->table.variables[vr[k]];
		const size_t i = v->source == FMU_SRC_PORT_POSITION || v->source == FMU_SRC_PORT_VELOCITY
		                     ? 3 * (size_t)inst->ports[v->index].particle + (size_t)v->component
		                     : 0;
		switch (v->source) {
		case FMU_SRC_PORT_POSITION: value[k] = u[i]; break;
		case FMU_SRC_PORT_VELOCITY: value[k] = a[i]; break;
		case FMU_SRC_ENERGY_DISSIPATED: value[k] = sm_model_dissipated_power(model, x, u); break;
		case FMU_SRC_ENERGY_INPUT: value[k] = sm_simulation_input_power(inst->sim); break;
		default: value[k] = state_output_change(inst, v, u, a, work, &evaluated); break;
		}
		if (!isfinite(value[k]) && overflowing == NULL)
			overflowing = v;
	}
	// As fmi2GetReal: derivatives beyond the range of a double are given with fmi2Warning.
	return fmu_overflow_warning(inst, fn, "the derivative of ", overflowing);
}

// springmass FMU: value references, and getting and setting values (fmi2GetReal to
// fmi2SetString). Parameters of the model file are set all or none, and a change of one after
// initialisation builds the model again; inputs are held until the next step gives them to the
// simulation; outputs are read from the simulation's current state.
#include "fmu_instance.h"

#include <float.h>
#include <math.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// Value references
// ---------------------------------------------------------------------------------------------

static const char* type_name(fmu_type t)
{
	return t == FMU_REAL ? "Real" : t == FMU_INTEGER ? "Integer" : t == FMU_BOOLEAN ? "Boolean" : "String";
}

// The variable of a value reference if it exists and has the type asked for.
const fmu_variable* fmu_lookup(instance* inst, const char* function, fmi2ValueReference vr, fmu_type type)
{
	if (vr >= (fmi2ValueReference)inst->table.count) {
		log_error(inst, "%s: unknown value reference %u (this FMU has %d variables)", function, (unsigned)vr,
		          (int)inst->table.count);
		return NULL;
	}
	const fmu_variable* v = &inst->table.variables[vr];
	if (v->type != type) {
		log_error(inst, "%s: value reference %u (%s) is %s %s variable, not %s", function, (unsigned)vr,
		          v->name, v->type == FMU_INTEGER ? "an" : "a", type_name(v->type), type_name(type));
		return NULL;
	}
	return v;
}

bool fmu_check_arrays(instance* inst, const char* function, const void* vr, size_t nvr, const void* value)
{
	if (nvr > 0 && (!vr || !value)) {
		log_error(inst, "%s: NULL array with nvr = %zu", function, nvr);
		return false;
	}
	return true;
}

// Whether a variable may be set now: parameters before initialisation ends (tunable ones also
// after), inputs always; nothing else ever.
static bool settable(instance* inst, const char* function, const fmu_variable* v)
{
	if (v->causality == FMU_INPUT) {
		if (inst->state & (ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE))
			return true;
	} else if (v->causality == FMU_PARAMETER) {
		if (inst->state & (ST_INSTANTIATED | ST_INITIALIZATION))
			return true;
		if (v->variability == FMU_TUNABLE && inst->state == ST_STEP_COMPLETE)
			return true;
		if (inst->state == ST_STEP_COMPLETE) {
			log_error(inst, "%s: %s is a fixed parameter: set it before fmi2ExitInitializationMode", function,
			          v->name);
			return false;
		}
	} else {
		log_error(inst, "%s: %s is %s and cannot be set", function, v->name,
		          v->causality == FMU_OUTPUT ? "an output" : "a local variable");
		return false;
	}
	log_error(inst, "%s: %s cannot be set in the FMU's current state (illegal call sequence)", function,
	          v->name);
	return false;
}

// Puts back the parameter values old[] that fmu_set_parameters recorded. Setting values takes memory:
// if they cannot be put back, the document and the simulation disagree, and the instance goes to
// the error state, from which fmi2SetFMUstate or fmi2Reset lead back.
void fmu_put_back_parameters(instance* inst, const char* function, const double* old)
{
	if (sm_document_set_parameters(inst->doc, old, NULL) != SM_OK) {
		log_error(inst,
		          "%s: the earlier parameter values cannot be put back (out of memory): the instance "
		          "is in the error state (fmi2SetFMUstate or fmi2Reset lead back)",
		          function);
		inst->state = ST_ERROR;
	}
}

// Sets the model-file parameters to values[] (one per parameter, in file order), all at once (a
// state or a call may change values that are valid only together, such as a rope's start and
// end), and records the previous ones in old[]. Returns false, with the document unchanged and
// the refusal logged, if the model rejects them.
bool fmu_set_parameters(instance* inst, const char* function, const double* values, double* old)
{
	int32_t np = sm_document_parameter_count(inst->doc);
	for (int32_t k = 0; k < np; ++k)
		old[k] = sm_document_parameter_value(inst->doc, k);
	sm_error err = {SM_OK, ""};
	if (sm_document_set_parameters(inst->doc, values, &err) != SM_OK) {
		log_error(inst, "%s: rejected by the model: %s", function, err.message);
		return false;
	}
	return true;
}

// Takes the numeric solver settings that a change of the model-file parameters changed (the file's
// "simulation" object may name parameters: "rtol": "tol"; such parameters are fixed). Setting such
// a parameter is setting its solver variable: "tol" as solver.rtol, which the experiment's
// tolerance then leaves alone. Only a change counts: a parameter set to the value it has (an
// importer writing every start value) leaves a solver variable set before it alone.
static void take_settings(instance* inst, const sm_simulation_def* before)
{
	const sm_simulation_def now = sm_document_get_settings(inst->doc).solver;
	sm_simulation_def* s = &inst->solver;
	if (now.relative_tolerance != before->relative_tolerance) {
		s->relative_tolerance = now.relative_tolerance;
		inst->rtol_set = true;
	}
#define TAKE_CHANGED(field)                                                                                  \
	do {                                                                                                     \
		if (now.field != before->field)                                                                      \
			s->field = now.field;                                                                            \
	} while (0)
	TAKE_CHANGED(absolute_tolerance_position);
	TAKE_CHANGED(absolute_tolerance_velocity);
	TAKE_CHANGED(max_step);
	TAKE_CHANGED(max_steps);
#undef TAKE_CHANGED
	// The method, the linear solver and the Jacobian are names in a model file, never parameters.
}

// Sets the model-file parameters among vr[] (all or none). Before initialisation ends the
// simulation is made again when next needed; afterwards (tunable parameters) the running
// simulation takes the new constants, built into one model, and keeps its state. A value the
// model rejects, alone or together with the others, puts every parameter back.
static fmi2Status set_model_parameters(instance* inst, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Real value[])
{
	// A call that changes no parameter (inputs alone, or every start value written back as it is)
	// changes nothing here, and takes a time in proportion to the values it sets, not to the
	// parameters: a master setting each input of a model with many parameters on its own went over
	// all of them for every value. Down to the sign of a zero, as the document tells -0 from 0.
	bool changes = false;
	for (size_t i = 0; i < nvr && !changes; ++i) {
		const fmu_variable* v = &inst->table.variables[vr[i]];
		changes = v->source == FMU_SRC_MODEL_PARAMETER && v->variability != FMU_CONSTANT &&
		          !fmu_same_parameter_value(sm_document_parameter_value(inst->doc, v->index), value[i]);
	}
	if (!changes)
		return fmi2OK;
	int32_t np = sm_document_parameter_count(inst->doc);
	double* values = inst->parameter_new;
	for (int32_t k = 0; k < np; ++k)
		values[k] = sm_document_parameter_value(inst->doc, k);
	// A constant takes only its own value (check_real), which it keeps as packaged: -0 is taken for
	// a constant of 0, but the model, which tells -0 from 0, is not given it.
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = &inst->table.variables[vr[i]];
		if (v->source == FMU_SRC_MODEL_PARAMETER && v->variability != FMU_CONSTANT)
			values[v->index] = value[i];
	}
	const double* old = inst->parameter_old;
	const sm_simulation_def settings = sm_document_get_settings(inst->doc).solver;
	if (!fmu_set_parameters(inst, "fmi2SetReal", values, inst->parameter_old))
		return fmi2Error;
	if (memcmp(values, old, (size_t)np * sizeof *values) == 0)
		return fmi2OK;
	sm_model* model = NULL;
	sm_status st = fmu_build_model(inst, "fmi2SetReal", old, &model);
	if (st == SM_OK && (inst->state & (ST_INSTANTIATED | ST_INITIALIZATION))) {
		sm_model_destroy(model);
		take_settings(inst, &settings);
		inst->sim_dirty = true;
		return fmi2OK;
	}
	if (st == SM_OK) {
		// Broken springs stay broken: the simulation's model has them disabled, those that broke
		// before a restored state included (the simulation itself knows only those that broke
		// since), and a new value of a constant does not mend them.
		const sm_model* running = sm_simulation_model(inst->sim);
		for (int32_t k = 0; k < inst->spring_count; ++k) {
			if (!sm_model_spring_enabled(running, k))
				sm_model_set_spring_enabled(model, k, false);
		}
		// The new constants change the energies at once (a stiffer spring holds more at the same
		// stretch): what sets them does that work, as a motion set elsewhere does.
		const sm_energies before = sm_simulation_energies(inst->sim);
		st = sm_simulation_update_model(inst->sim, model);
		if (st != SM_OK) {
			log_error(inst, "fmi2SetReal: the simulation cannot take the new parameters: %s",
			          sm_simulation_last_error(inst->sim));
		} else {
			const sm_energies after = sm_simulation_energies(inst->sim);
			inst->work_offset += (after.kinetic - before.kinetic) + (after.elastic - before.elastic) +
			                     (after.gravity - before.gravity);
		}
	}
	sm_model_destroy(model);
	if (st != SM_OK) {
		fmu_put_back_parameters(inst, "fmi2SetReal", old);
		return fmi2Error;
	}
	fmu_forget_derived_values(inst);
	for (int32_t k = 0; k < np; ++k) {
		if (values[k] != old[k] && fmu_logging(inst, LOG_EVENTS))
			fmu_logf(inst, fmi2OK, LOG_EVENTS, "t = %s: parameter %s = %s (solver restarted)",
			         fmu_number_text(inst->time).text, sm_document_parameter_name(inst->doc, k),
			         fmu_number_text(values[k]).text);
	}
	return fmi2OK;
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0: getting and setting values
// ---------------------------------------------------------------------------------------------

// The energies, evaluated once per state: the three energy outputs share one pass over the
// particles and springs, and the end of a step's check of the outputs and the master's reads after
// it share that pass too.
const sm_energies* fmu_current_energies(instance* inst)
{
	if (!inst->energies_valid) {
		inst->energies = sm_simulation_energies(inst->sim);
		inst->energies_valid = true;
	}
	return &inst->energies;
}

double fmu_real_value(instance* inst, const fmu_variable* v)
{
	const double* x = inst->sim ? sm_simulation_positions(inst->sim) : NULL;
	const double* u = inst->sim ? sm_simulation_velocities(inst->sim) : NULL;
	switch (v->source) {
	case FMU_SRC_MODEL_PARAMETER: return sm_document_parameter_value(inst->doc, v->index);
	case FMU_SRC_SOLVER_RTOL: return inst->solver.relative_tolerance;
	case FMU_SRC_SOLVER_ATOL_POSITION: return inst->solver.absolute_tolerance_position;
	case FMU_SRC_SOLVER_ATOL_VELOCITY: return inst->solver.absolute_tolerance_velocity;
	case FMU_SRC_SOLVER_MAX_STEP: return inst->solver.max_step;
	case FMU_SRC_PORT_POSITION:
		if (v->causality == FMU_INPUT)
			return inst->held[v->index].position[v->component];
		return x[3 * inst->ports[v->index].particle + v->component];
	case FMU_SRC_PORT_VELOCITY:
		if (v->causality == FMU_INPUT)
			return inst->held[v->index].velocity[v->component];
		return u[3 * inst->ports[v->index].particle + v->component];
	case FMU_SRC_PORT_FORCE:
		if (v->causality == FMU_INPUT)
			return inst->held[v->index].force[v->component];
		return fmu_current_forces(inst)[3 * inst->ports[v->index].particle + v->component];
	case FMU_SRC_PARTICLE_POSITION: return x[3 * v->index + v->component];
	case FMU_SRC_PARTICLE_VELOCITY: return u[3 * v->index + v->component];
	case FMU_SRC_ENERGY_KINETIC: return fmu_current_energies(inst)->kinetic;
	case FMU_SRC_ENERGY_ELASTIC: return fmu_current_energies(inst)->elastic;
	case FMU_SRC_ENERGY_GRAVITY: return fmu_current_energies(inst)->gravity;
	case FMU_SRC_ENERGY_DISSIPATED: return fmu_dissipated_energy(inst);
	case FMU_SRC_ENERGY_INPUT: return fmu_input_work(inst);
	default: return NAN;
	}
}

// fmi2OK, or fmi2Warning, logged, when a value read (`what`: "" or "the derivative of ") of
// `overflowing` is beyond the range of a double.
fmi2Status fmu_overflow_warning(instance* inst, const char* function, const char* what,
                                const fmu_variable* overflowing)
{
	if (overflowing == NULL)
		return fmi2OK;
	fmu_logf(inst, fmi2Warning, LOG_WARNING,
	         "%s: %s%s is not finite: the inputs or the state put the model beyond the range of a double",
	         function, what, overflowing->name);
	return fmi2Warning;
}

// Whether a variable's value needs the simulation (everything but parameters, constants and
// inputs).
static bool needs_simulation(const fmu_variable* v)
{
	return v->source >= FMU_SRC_PORT_POSITION && v->causality != FMU_INPUT;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetReal", ST_RUNNING) ||
	    !fmu_check_arrays(inst, "fmi2GetReal", vr, nvr, value))
		return fmi2Error;
	// The simulation, with the inputs set, is made ready once for the whole call: once per variable,
	// each output read went over every port (fmu_apply_inputs), and reading all the outputs of a model
	// with many ports took a time in proportion to their product.
	bool simulation = false;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2GetReal", vr[i], FMU_REAL);
		if (!v)
			return fmi2Error;
		simulation = simulation || needs_simulation(v);
	}
	if (simulation) {
		const bool rebuild = !inst->sim || inst->sim_dirty || inst->state == ST_INITIALIZATION;
		const fmi2Status ready =
		    rebuild ? fmu_ensure_simulation(inst, "fmi2GetReal") : fmu_apply_inputs(inst, "fmi2GetReal");
		if (ready != fmi2OK)
			return fmi2Error;
	}
	const fmu_variable* overflowing = NULL;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = &inst->table.variables[vr[i]];
		value[i] = fmu_real_value(inst, v);
		if (!isfinite(value[i]) && overflowing == NULL)
			overflowing = v;
	}
	// A finite state whose outputs overflow (an input far beyond the model's scale, such as a
	// motion port at 1e300 m, whose spring's squared length does): the values are given, as they
	// are, with fmi2Warning and the first such variable named; a step from here is discarded.
	return fmu_overflow_warning(inst, "fmi2GetReal", "", overflowing);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetInteger", ST_RUNNING) ||
	    !fmu_check_arrays(inst, "fmi2GetInteger", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2GetInteger", vr[i], FMU_INTEGER);
		if (!v)
			return fmi2Error;
		value[i] = v->source == FMU_SRC_SOLVER_THREADS ? inst->solver.threads : inst->solver.max_steps;
	}
	return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetBoolean", ST_RUNNING) ||
	    !fmu_check_arrays(inst, "fmi2GetBoolean", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		if (!fmu_lookup(inst, "fmi2GetBoolean", vr[i], FMU_BOOLEAN))
			return fmi2Error;
		value[i] = inst->solver.stability_limit_detection ? fmi2True : fmi2False;
	}
	return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetString", ST_RUNNING) ||
	    !fmu_check_arrays(inst, "fmi2GetString", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2GetString", vr[i], FMU_STRING);
		if (!v)
			return fmi2Error;
		switch (v->source) {
		case FMU_SRC_SOLVER_METHOD: value[i] = sm_method_name(inst->solver.method); break;
		case FMU_SRC_SOLVER_LINEAR_SOLVER: value[i] = sm_linear_solver_name(inst->solver.solver); break;
		case FMU_SRC_SOLVER_INPUT_CHANGES:
			value[i] = sm_input_changes_name(inst->solver.restart_on_input_change);
			break;
		default: value[i] = sm_jacobian_variant_name(inst->solver.jacobian); break;
		}
	}
	return fmi2OK;
}

// Whether value may be given to v now: finite, settable in this state, and in the range of a
// solver setting. Model-file parameters are checked by the model when they are set.
static bool check_real(instance* inst, const fmu_variable* v, double value)
{
	if (!isfinite(value)) {
		log_error(inst, "fmi2SetReal: %s = %g rejected: values must be finite", v->name, value);
		return false;
	}
	// A constant keeps its value; setting that value (an importer passing every start value)
	// changes nothing and is allowed.
	if (v->variability == FMU_CONSTANT) {
		if (value == sm_document_parameter_value(inst->doc, v->index))
			return true;
		log_error(inst,
		          "fmi2SetReal: %s = %s refused: %s sets the model's structure, " PACKAGED_STRUCTURE "%s=%s)",
		          v->name, fmu_number_text(value).text, v->name, v->name, fmu_number_text(value).text);
		return false;
	}
	if (!settable(inst, "fmi2SetReal", v))
		return false;
	bool tolerance = v->source == FMU_SRC_SOLVER_RTOL || v->source == FMU_SRC_SOLVER_ATOL_POSITION ||
	                 v->source == FMU_SRC_SOLVER_ATOL_VELOCITY;
	if (tolerance && (!(value > 0.0) || (v->source == FMU_SRC_SOLVER_RTOL && !(value < 1.0)))) {
		log_error(inst, "fmi2SetReal: %s = %g rejected: tolerances must be > 0, a relative one < 1", v->name,
		          value);
		return false;
	}
	if (v->source == FMU_SRC_SOLVER_RTOL && !(value >= SM_MIN_RELATIVE_TOLERANCE)) {
		log_error(inst,
		          "fmi2SetReal: %s = %s rejected: a relative tolerance must be at least %s, the machine "
		          "epsilon (CVODE cannot meet a smaller one)",
		          v->name, fmu_number_text(value).text, fmu_number_text(SM_MIN_RELATIVE_TOLERANCE).text);
		return false;
	}
	if (tolerance && v->source != FMU_SRC_SOLVER_RTOL && !(value >= SM_MIN_ABSOLUTE_TOLERANCE)) {
		log_error(inst,
		          "fmi2SetReal: %s = %s rejected: an absolute tolerance must be at least %s (CVODE's error "
		          "norm overflows below)",
		          v->name, fmu_number_text(value).text, fmu_number_text(SM_MIN_ABSOLUTE_TOLERANCE).text);
		return false;
	}
	if (v->source == FMU_SRC_SOLVER_MAX_STEP && value < 0.0) {
		log_error(inst, "fmi2SetReal: %s = %g rejected: must be >= 0 (0: unlimited)", v->name, value);
		return false;
	}
	// As a model file's max_step (SM_MAX_STEP_FLOOR, simulation.h).
	if (v->source == FMU_SRC_SOLVER_MAX_STEP && value > 0.0 && value <= SM_MAX_STEP_FLOOR) {
		log_error(
		    inst,
		    "fmi2SetReal: %s = %s rejected: must be 0 (unlimited) or above %s s, 1 / DBL_MAX: CVODE takes "
		    "its inverse",
		    v->name, fmu_number_text(value).text, fmu_number_text(SM_MAX_STEP_FLOOR).text);
		return false;
	}
	return true;
}

// Sets a checked value of anything but a model-file parameter.
static void set_real(instance* inst, const fmu_variable* v, double value)
{
	switch (v->source) {
	case FMU_SRC_SOLVER_RTOL:
		inst->solver.relative_tolerance = value;
		inst->rtol_set = true;
		inst->sim_dirty = true;
		break;
	case FMU_SRC_SOLVER_ATOL_POSITION:
		inst->solver.absolute_tolerance_position = value;
		inst->sim_dirty = true;
		break;
	case FMU_SRC_SOLVER_ATOL_VELOCITY:
		inst->solver.absolute_tolerance_velocity = value;
		inst->sim_dirty = true;
		break;
	case FMU_SRC_SOLVER_MAX_STEP:
		inst->solver.max_step = value;
		inst->sim_dirty = true;
		break;
	case FMU_SRC_PORT_POSITION:
	case FMU_SRC_PORT_VELOCITY:
	case FMU_SRC_PORT_FORCE: {
		port_values* h = &inst->held[v->index];
		double* slot = v->source == FMU_SRC_PORT_POSITION   ? &h->position[v->component]
		               : v->source == FMU_SRC_PORT_VELOCITY ? &h->velocity[v->component]
		                                                    : &h->force[v->component];
		*slot = value;
		inst->port_dirty[v->index] = true;
		fmu_forget_derived_values(inst);
		break;
	}
	default: break;
	}
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetReal", ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !fmu_check_arrays(inst, "fmi2SetReal", vr, nvr, value))
		return fmi2Error;
	// A rejected call changes nothing: every value is checked first, then the model-file
	// parameters are set together (and put back if the model rejects them), then the rest.
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2SetReal", vr[i], FMU_REAL);
		if (!v || !check_real(inst, v, value[i]))
			return fmi2Error;
	}
	if (set_model_parameters(inst, vr, nvr, value) != fmi2OK)
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i)
		set_real(inst, &inst->table.variables[vr[i]], value[i]);
	return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetInteger", ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !fmu_check_arrays(inst, "fmi2SetInteger", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2SetInteger", vr[i], FMU_INTEGER);
		if (!v || !settable(inst, "fmi2SetInteger", v))
			return fmi2Error;
		if (value[i] < 1) {
			log_error(inst, "fmi2SetInteger: %s = %d rejected: must be >= 1", v->name, (int)value[i]);
			return fmi2Error;
		}
	}
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2SetInteger", vr[i], FMU_INTEGER);
		*(v->source == FMU_SRC_SOLVER_THREADS ? &inst->solver.threads : &inst->solver.max_steps) = value[i];
		inst->sim_dirty = true;
	}
	return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetBoolean", ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !fmu_check_arrays(inst, "fmi2SetBoolean", vr, nvr, value))
		return fmi2Error;
	// The only Boolean variable is solver.stability_limit_detection. A value other than fmi2True
	// and fmi2False is refused, and a refused call changes nothing.
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2SetBoolean", vr[i], FMU_BOOLEAN);
		if (!v || !settable(inst, "fmi2SetBoolean", v))
			return fmi2Error;
		if (value[i] != fmi2True && value[i] != fmi2False) {
			log_error(inst, "fmi2SetBoolean: %s = %d rejected: must be fmi2True (1) or fmi2False (0)",
			          v->name, (int)value[i]);
			return fmi2Error;
		}
	}
	for (size_t i = 0; i < nvr; ++i) {
		inst->solver.stability_limit_detection = value[i] == fmi2True;
		inst->sim_dirty = true;
	}
	return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetString", ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !fmu_check_arrays(inst, "fmi2SetString", vr, nvr, value))
		return fmi2Error;
	sm_simulation_def solver = inst->solver;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = fmu_lookup(inst, "fmi2SetString", vr[i], FMU_STRING);
		if (!v || !settable(inst, "fmi2SetString", v))
			return fmi2Error;
		int bad = 0;
		if (!value[i]) {
			bad = 1;
		} else if (v->source == FMU_SRC_SOLVER_METHOD) {
			bad = sm_method_from_name(value[i], &solver.method) != SM_OK;
		} else if (v->source == FMU_SRC_SOLVER_LINEAR_SOLVER) {
			bad = sm_linear_solver_from_name(value[i], &solver.solver) != SM_OK;
		} else if (v->source == FMU_SRC_SOLVER_INPUT_CHANGES) {
			bad = sm_input_changes_from_name(value[i], &solver.restart_on_input_change) != SM_OK;
		} else {
			bad = sm_jacobian_variant_from_name(value[i], &solver.jacobian) != SM_OK;
		}
		if (bad) {
			log_error(inst, "fmi2SetString: %s = \"%s\" rejected: %s", v->name,
			          value[i] ? value[i] : "(null)", v->description);
			return fmi2Error;
		}
	}
	inst->solver = solver;
	if (nvr > 0)
		inst->sim_dirty = true;
	return fmi2OK;
}

// springmass FMU: the FMI 2.0 Co-Simulation entry points of the generic FMU binary.
//
// One binary serves every model: fmi2Instantiate reads resources/model.json and, when the FMU
// was packaged with parameter values (springmass fmu --set), resources/parameters.txt, checks
// that their hash is the GUID the importer passes, applies those values to the parsed file (again
// at every fmi2Reset) and builds the same variable table (fmu_model.c) the packager wrote
// modelDescription.xml from. The glue uses the public springmass API only (model files and
// simulations) and knows nothing of force laws.
//
// Every entry point checks the states in which FMI 2.0 allows it ("illegal call sequence"
// otherwise), its pointers and value references, and returns fmi2Error with a logged message
// rather than ever crashing the importer. There is no global state: each instance owns its
// document, its simulation and its buffers.
//
// The FMU state (fmi2GetFMUstate to fmi2DeSerializeFMUstate) is in fmu_state.c; the instance and
// the helpers both files call are declared in fmu_instance.h and defined here.
#define _POSIX_C_SOURCE 200809L
#include "fmu_instance.h"
#include "text_file.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// Logging
// ---------------------------------------------------------------------------------------------

// The names of the log categories (fmu_instance.h), in the order of their bits.
static const char* const category_names[] = {"logEvents", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logSolver"};
#define LOG_CATEGORY_COUNT 5
// Warnings, discards and errors are reported unless switched off explicitly; events and solver
// statistics are debug output, on when logging is.
#define LOG_ALWAYS (LOG_WARNING | LOG_DISCARD | LOG_ERROR)

// Logs a message in a category if that category is on. The text is formatted here and handed to
// the importer's logger with '%' and '#' doubled: FMI 2.0 (2.1.5) loggers treat the message as a
// printf format, and '#' as their escape character ("#r12#" names the Real variable of value
// reference 12, "##" is a '#'), so text a message quotes (a path, a category, a string value) is
// shown as it was given. Numbers are written in the C locale whatever the importer's LC_NUMERIC:
// under a decimal comma a message's "n = 0,5, m = 2" is ambiguous and a command it suggests
// (springmass fmu ... --set l0=0,5) is refused. uselocale() switches the calling thread only;
// glibc's "C" locale object is static (no allocation).
static bool logging(const instance* inst, unsigned category)
{
	return inst && inst->logger && (inst->log_mask & category);
}

void fmu_logf(instance* inst, fmi2Status status, unsigned category, const char* fmt, ...)
{
	if (!logging(inst, category))
		return;
	// Most messages fit the buffer on the stack; a longer one (a resource path of some 500 bytes
	// named twice) is formatted again whole on the heap (without memory for it, it stays cut).
	char buffer[1024];
	char* text = buffer;
	va_list args, again;
	const locale_t c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0);
	const locale_t previous = c_locale != (locale_t)0 ? uselocale(c_locale) : (locale_t)0;
	va_start(args, fmt);
	va_copy(again, args);
	const int length = vsnprintf(buffer, sizeof buffer, fmt, args);
	if (length >= (int)sizeof buffer) {
		char* whole = malloc((size_t)length + 1);
		if (whole != NULL) {
			vsnprintf(whole, (size_t)length + 1, fmt, again);
			text = whole;
		}
	}
	va_end(again);
	va_end(args);
	if (c_locale != (locale_t)0) {
		uselocale(previous);
		freelocale(c_locale);
	}
	const size_t size = 2 * strlen(text) + 1;
	char escaped_buffer[2 * sizeof buffer];
	char* escaped = size <= sizeof escaped_buffer ? escaped_buffer : malloc(size);
	if (escaped == NULL) {
		if (text != buffer)
			free(text);
		return;
	}
	size_t k = 0;
	for (size_t i = 0; text[i]; ++i) {
		if (text[i] == '%' || text[i] == '#')
			escaped[k++] = text[i];
		escaped[k++] = text[i];
	}
	escaped[k] = '\0';
	if (text != buffer)
		free(text);
	int index = 0;
	while (index < LOG_CATEGORY_COUNT && (1u << index) != category)
		++index;
	inst->logger(inst->environment, inst->name, status,
	             index < LOG_CATEGORY_COUNT ? category_names[index] : "logAll", escaped);
	if (escaped != escaped_buffer)
		free(escaped);
}

// A number for a message, in the fewest digits that read back to it (0.3, not
// 0.29999999999999999). Used as fmu_number_text(x).text within one call: the returned struct lives
// until the end of the full expression that contains the call.
number_text_t fmu_number_text(double x)
{
	number_text_t t;
	sm_format_number(x, t.text);
	return t;
}

// Checks the state machine: logs and returns false if `function` is not allowed now.
bool fmu_allowed(instance* inst, const char* function, int states)
{
	if (!inst)
		return false;
	if (!(inst->state & states)) {
		log_error(inst, "%s: illegal call sequence (not allowed in the FMU's current state: %s)", function,
		          inst->state == ST_INSTANTIATED     ? "instantiated"
		          : inst->state == ST_INITIALIZATION ? "initialization mode"
		          : inst->state == ST_STEP_COMPLETE  ? "step complete"
		          : inst->state == ST_STEP_FAILED    ? "step failed"
		          : inst->state == ST_TERMINATED     ? "terminated"
		                                             : "error");
		return false;
	}
	return true;
}

// ---------------------------------------------------------------------------------------------
// Resources
// ---------------------------------------------------------------------------------------------

static int hex_value(char c)
{
	if (c >= '0' && c <= '9')
		return c - '0';
	if (c >= 'a' && c <= 'f')
		return c - 'a' + 10;
	if (c >= 'A' && c <= 'F')
		return c - 'A' + 10;
	return -1;
}

// Whether text starts with a URI scheme and an authority, "scheme://" (RFC 3986 3.1: a letter,
// then letters, digits, '+', '-' or '.'). A path may contain "://" further on.
static bool starts_with_scheme(const char* text)
{
	if (!isalpha((unsigned char)text[0]))
		return false;
	size_t i = 1;
	while (isalnum((unsigned char)text[i]) || text[i] == '+' || text[i] == '-' || text[i] == '.')
		i++;
	return strncmp(text + i, "://", 3) == 0;
}

// Whether text starts with prefix, letters compared without case (RFC 3986 3.1 and 3.2.2: scheme
// and host are case-insensitive).
static bool starts_with_ci(const char* text, const char* prefix)
{
	for (; *prefix; ++text, ++prefix) {
		if (tolower((unsigned char)*text) != tolower((unsigned char)*prefix))
			return false;
	}
	return true;
}

// The file-system path of a resource URI: file:///dir, file:/dir, file://localhost/dir (scheme
// and host in any case), percent-escapes decoded, or a plain path, taken as it is (a path escapes
// nothing: its "%41" is a folder's name, not "A"). Returns a malloc'ed path without a trailing
// '/', or NULL for a URI of another host or scheme and for an escaped NUL (which would cut the path
// short), or with *out_of_memory set when the path cannot be allocated.
static char* resource_path(const char* uri, bool* out_of_memory)
{
	*out_of_memory = false;
	const char* p = uri;
	bool escaped = true;
	if (starts_with_ci(p, "file://localhost/"))
		p += 16;
	else if (starts_with_ci(p, "file:///"))
		p += 7;
	else if (starts_with_ci(p, "file://"))
		return NULL;  // file://host/... on another host
	else if (starts_with_ci(p, "file:/"))
		p += 5;
	else if (starts_with_ci(p, "file:") || starts_with_scheme(p))
		return NULL;  // a relative file URI, or another scheme
	else
		escaped = false;
	size_t n = strlen(p);
	char* path = malloc(n + 1);
	if (!path) {
		*out_of_memory = true;
		return NULL;
	}
	size_t k = 0;
	for (size_t i = 0; i < n; ++i) {
		if (escaped && p[i] == '%' && i + 2 < n && hex_value(p[i + 1]) >= 0 && hex_value(p[i + 2]) >= 0) {
			path[k] = (char)(hex_value(p[i + 1]) * 16 + hex_value(p[i + 2]));
			if (path[k++] == '\0') {
				free(path);
				return NULL;
			}
			i += 2;
		} else {
			path[k++] = p[i];
		}
	}
	while (k > 1 && path[k - 1] == '/')
		--k;
	path[k] = '\0';
	return path;
}

// ---------------------------------------------------------------------------------------------
// Model and simulation
// ---------------------------------------------------------------------------------------------

// Start values of inputs and settings from the document and the table.
static void load_start_values(instance* inst)
{
	sm_document_settings settings = sm_document_get_settings(inst->doc);
	inst->solver = settings.solver;
	// An input set is a jump of the right-hand side when its value changes (a force switched on,
	// a drive that moves off its extrapolated path; the simulation compares): CVODE restarts then
	// instead of stepping its high-order history across the discontinuity, which at tight
	// tolerances fails with repeated error-test failures. Inputs set to what they were keep the
	// history.
	inst->solver.restart_on_input_change = true;
	inst->rtol_set = false;
	for (int32_t p = 0; p < inst->port_count; ++p) {
		memset(&inst->held[p], 0, sizeof inst->held[p]);
		inst->port_dirty[p] = true;
	}
	for (int32_t i = 0; i < inst->table.count; ++i) {
		const fmu_variable* v = &inst->table.variables[i];
		if (v->causality != FMU_INPUT)
			continue;
		port_values* h = &inst->held[v->index];
		if (v->source == FMU_SRC_PORT_POSITION)
			h->position[v->component] = v->start_real;
		else if (v->source == FMU_SRC_PORT_VELOCITY)
			h->velocity[v->component] = v->start_real;
		else if (v->source == FMU_SRC_PORT_FORCE)
			h->force[v->component] = v->start_real;
	}
}

// Appends "name = value" of every parameter whose value differs from before[] to text (size bytes,
// NUL-terminated), comma-separated.
static void changed_parameters(const instance* inst, const double* before, char* text, size_t size)
{
	size_t k = 0;
	text[0] = '\0';
	for (int32_t i = 0; i < sm_document_parameter_count(inst->doc) && k < size; ++i) {
		double value = sm_document_parameter_value(inst->doc, i);
		if (value != before[i]) {
			int n = snprintf(text + k, size - k, "%s%s = %s", k ? ", " : "",
			                 sm_document_parameter_name(inst->doc, i), fmu_number_text(value).text);
			k += n > 0 ? (size_t)n : 0;
		}
	}
}

// Whether a model built from the document has the structure the FMU's variables were made for at
// packaging: the particle and spring counts of fmi2Instantiate and every port at its particle.
// p[i].x and the ports name particles by index, and the instance's buffers are sized for those
// counts, so a parameter value that changes them is refused (logged, naming the parameters that
// differ from before[], which may be NULL) rather than ever taken.
static bool packaged_structure(instance* inst, const char* function, const sm_model* model,
                               const double* before)
{
	int32_t n = sm_model_particle_count(model), m = sm_model_spring_count(model);
	char what[160] = "";
	if (n != inst->particle_count || m != inst->spring_count) {
		snprintf(what, sizeof what, "%d particles and %d springs instead of %d and %d", (int)n, (int)m,
		         (int)inst->particle_count, (int)inst->spring_count);
	}
	for (int32_t p = 0; !what[0] && p < inst->port_count; ++p) {
		if (sm_document_port(inst->doc, p).particle != inst->ports[p].particle)
			snprintf(what, sizeof what, "port %s at particle %d instead of %d", inst->ports[p].name,
			         (int)sm_document_port(inst->doc, p).particle, (int)inst->ports[p].particle);
	}
	if (!what[0])
		return true;
	char names[512] = "the parameters";
	if (before)
		changed_parameters(inst, before, names, sizeof names);
	log_error(inst, "%s: %s would give the model %s, but " PACKAGED_STRUCTURE "NAME=VALUE)", function, names,
	          what);
	return false;
}

// Builds the model with the current parameter values, motion ports' particles driven; refuses a
// model of another structure than the packaged one (packaged_structure, naming the parameters
// that differ from before[], or NULL).
sm_status fmu_build_model(instance* inst, const char* function, const double* before, sm_model** out)
{
	sm_error err = {SM_OK, ""};
	sm_model* model = NULL;
	sm_status st = sm_document_build(inst->doc, &model, &err);
	if (st != SM_OK) {
		log_error(inst, "%s: cannot build the model: %s", function, err.message);
		return st;
	}
	if (!packaged_structure(inst, function, model, before)) {
		sm_model_destroy(model);
		return SM_ERROR_TOPOLOGY;
	}
	for (int32_t p = 0; p < inst->port_count; ++p) {
		if (inst->ports[p].kind != SM_PORT_MOTION)
			continue;
		sm_particle_def def;
		sm_model_get_particle(model, inst->ports[p].particle, &def);
		if (def.motion != SM_PARTICLE_DRIVEN) {
			st = sm_model_set_particle_motion(model, inst->ports[p].particle, SM_PARTICLE_DRIVEN);
			if (st != SM_OK) {
				log_error(inst, "%s: cannot drive the particle of motion port %s: %s", function,
				          inst->ports[p].name, sm_model_last_error(model));
				sm_model_destroy(model);
				return st;
			}
		}
	}
	*out = model;
	return SM_OK;
}

// Gives a port's inputs to a simulation from its current time on: a motion port's position,
// velocity and acceleration, a force port's force and rate, as held (position and force given, or
// NULL for the held ones).
static sm_status give_port_inputs(sm_simulation* sim, const sm_port* port, const port_values* h,
                                  const double* position, const double* velocity, const double* force)
{
	if (port->kind == SM_PORT_MOTION)
		return sm_simulation_set_driven_accelerating(sim, port->particle, position ? position : h->position,
		                                             velocity ? velocity : h->velocity, h->acceleration);
	if (port->kind == SM_PORT_FORCE)
		return sm_simulation_set_external_force_ramp(sim, port->particle, force ? force : h->force,
		                                             h->force_rate);
	return SM_OK;
}

// Gives the inputs set since the last step to the simulation, at the current communication point:
// a motion port set in a step moves from its held position with its held velocity (and
// acceleration) from the step's start, a force port pushes with its held force (and rate), whether
// or not a value changed (the simulation restarts CVODE only where the motion leaves its
// extrapolated path, or a force its ramp). Ports not set since keep their motion and ramp.
static fmi2Status apply_inputs(instance* inst, const char* function)
{
	for (int32_t p = 0; p < inst->port_count; ++p) {
		if (!inst->port_dirty[p])
			continue;
		port_values* h = &inst->held[p];
		const sm_status st = give_port_inputs(inst->sim, &inst->ports[p], h, NULL, NULL, NULL);
		h->since = sm_simulation_time(inst->sim);
		if (st != SM_OK) {
			log_error(inst, "%s: port %s: cannot apply its inputs: %s", function, inst->ports[p].name,
			          sm_simulation_last_error(inst->sim));
			return fmi2Error;
		}
		inst->port_dirty[p] = false;
		fmu_forget_derived_values(inst);
	}
	// Inputs set in initialisation mode give the initial state: they do no work.
	if (inst->state == ST_INITIALIZATION) {
		inst->work_origin = sm_simulation_input_work(inst->sim);
		inst->work_offset = 0.0;
	}
	return fmi2OK;
}

// Creates the simulation from a model at time start_time + sim_time with the given state (or the
// model's initial state when x is NULL), the solver settings and the port inputs given (held, and
// pending: which ports have inputs set that no step has taken yet), and makes it the instance's
// only when all of that succeeded: a failure changes nothing. The inputs' work counts from the
// state given (work_origin): what giving the ports their inputs does belongs to it, except the
// pending inputs of a restored state, which its run had yet to give (as fmi2DoStep would).
fmi2Status fmu_create_simulation(instance* inst, const char* function, sm_model* model,
                                 const sm_simulation_def* solver, const port_values* held,
                                 const bool* pending, double sim_time, const double* x, const double* v)
{
	sm_error err = {SM_OK, ""};
	sm_simulation* sim = sm_simulation_create(model, solver, &err);
	if (!sim) {
		log_error(inst, "%s: cannot create the simulation: %s", function, err.message);
		return fmi2Error;
	}
	if (x && sm_simulation_set_state(sim, sim_time, x, v) != SM_OK) {
		log_error(inst, "%s: cannot restore the state: %s", function, sm_simulation_last_error(sim));
		sm_simulation_destroy(sim);
		return fmi2Error;
	}
	// A restored motion port continues from where its particle is, with the velocity it has there:
	// the prescribed motion of a port whose inputs were set some steps before the state was saved
	// has moved on since (the held position is still what the input reads). A restored force port
	// goes on along its ramp from the value it reached. Inputs set since the last step (pending[p])
	// start from the held values, as at fmi2DoStep: after every port has its particle where the
	// state has it (pass 1), so that the work counts their jumps from there.
	double work_origin = 0.0;
	for (int pass = 0; pass < 2; ++pass) {
		for (int32_t p = 0; p < inst->port_count; ++p) {
			const bool continued = x && pass == 0;
			if (pass == 1 && !(x && pending[p]))
				continue;
			const size_t i = 3 * (size_t)inst->ports[p].particle;
			double force[3];
			for (int c = 0; c < 3; c++)
				force[c] = held[p].force[c] + held[p].force_rate[c] * (sim_time - held[p].since);
			const sm_status st = continued
			                         ? give_port_inputs(sim, &inst->ports[p], &held[p], x + i, v + i, force)
			                         : give_port_inputs(sim, &inst->ports[p], &held[p], NULL, NULL, NULL);
			if (st != SM_OK) {
				log_error(inst, "%s: port %s: cannot apply its inputs: %s", function, inst->ports[p].name,
				          sm_simulation_last_error(sim));
				sm_simulation_destroy(sim);
				return fmi2Error;
			}
		}
		if (pass == 0)
			work_origin = sm_simulation_input_work(sim);
	}
	sm_simulation_destroy(inst->sim);
	inst->sim = sim;
	if (solver != &inst->solver)
		inst->solver = *solver;
	if (held != inst->held)
		memcpy(inst->held, held, (size_t)inst->port_count * sizeof *held);
	for (int32_t p = 0; p < inst->port_count; ++p) {
		if (!x || pending[p])
			inst->held[p].since = sim_time;
		inst->port_dirty[p] = false;
	}
	fmu_forget_derived_values(inst);
	inst->sim_dirty = false;
	inst->breaks_logged = 0;
	inst->dissipated_offset = 0.0;
	inst->work_origin = work_origin;
	inst->work_offset = 0.0;
	return fmi2OK;
}

// Makes sure a simulation with the current settings exists (initialisation mode and later).
fmi2Status fmu_ensure_simulation(instance* inst, const char* function)
{
	if (inst->sim && !inst->sim_dirty)
		return apply_inputs(inst, function);
	sm_model* model = NULL;
	if (fmu_build_model(inst, function, NULL, &model) != SM_OK)
		return fmi2Error;
	fmi2Status status = fmu_create_simulation(inst, function, model, &inst->solver, inst->held,
	                                          inst->port_dirty, 0.0, NULL, NULL);
	sm_model_destroy(model);
	if (status == fmi2OK)
		inst->time = inst->start_time;
	return status;
}

// The simulation's dissipated energy since it was created plus what a restored state carried
// (dissipated_offset: the state's value minus the new simulation's, which starts at 0, so the
// restored value itself). By physics it is non-negative: the integral of the damping power, a
// sum of terms kd r^2 and c m |v|^2, each >= 0, plus the elastic energy of the springs that broke. The sum of
// two non-negative doubles rounds to a non-negative one, so the offset adds no sign error; but the
// simulation's own value may dip below 0 by round-off where it is near 0: CVODE's BDF formulas
// of order 3 and more and its interpolation between steps do not keep an integral of a
// non-negative rate monotone.
// (No dip was seen: over every internal step of the bundled models at three tolerances the least
// value was 0.) Such a dip is the error of a value at 0 and is shown as 0, so that every value
// read and every state saved is >= 0, and a restored state may require it to be (fmu_state.c).
double fmu_dissipated_energy(const instance* inst)
{
	return fmax(0.0, sm_simulation_dissipated_energy(inst->sim) + inst->dissipated_offset);
}

// The work since work_origin is taken before the offset is added: right after a restore it is 0
// exactly, and the value read is the state's, to the bit. Added to the offset first (-origin +
// the state's work), the origin's round-off stayed in it: -0.8144713640090189 J read back from a
// state that carried -0.814471364009019 J, its motion port's particle away from where the model
// starts it.
double fmu_input_work(const instance* inst)
{
	return (sm_simulation_input_work(inst->sim) - inst->work_origin) + inst->work_offset;
}

void fmu_forget_derived_values(instance* inst)
{
	inst->forces_valid = false;
	inst->energies_valid = false;
}

static const double* current_forces(instance* inst)
{
	if (!inst->forces_valid) {
		sm_simulation_forces(inst->sim, inst->forces);
		inst->forces_valid = true;
	}
	return inst->forces;
}

// ---------------------------------------------------------------------------------------------
// Value references
// ---------------------------------------------------------------------------------------------

static const char* type_name(fmu_type t)
{
	return t == FMU_REAL ? "Real" : t == FMU_INTEGER ? "Integer" : "String";
}

// The variable of a value reference if it exists and has the type asked for.
static const fmu_variable* lookup(instance* inst, const char* function, fmi2ValueReference vr, fmu_type type)
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

static bool check_arrays(instance* inst, const char* function, const void* vr, size_t nvr, const void* value)
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
		if (values[k] != old[k] && logging(inst, LOG_EVENTS))
			fmu_logf(inst, fmi2OK, LOG_EVENTS, "t = %s: parameter %s = %s (solver restarted)",
			         fmu_number_text(inst->time).text, sm_document_parameter_name(inst->doc, k),
			         fmu_number_text(values[k]).text);
	}
	return fmi2OK;
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0: inquiry, logging, instantiation
// ---------------------------------------------------------------------------------------------

const char* fmi2GetTypesPlatform(void)
{
	return fmi2TypesPlatform;
}

const char* fmi2GetVersion(void)
{
	return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetDebugLogging", ST_ANY))
		return fmi2Error;
	if (nCategories > 0 && !categories) {
		log_error(inst, "fmi2SetDebugLogging: NULL categories with nCategories = %zu", nCategories);
		return fmi2Error;
	}
	unsigned mask = 0;
	if (nCategories == 0) {
		mask = (1u << LOG_CATEGORY_COUNT) - 1u;
	}
	for (size_t i = 0; i < nCategories; ++i) {
		int k = 0;
		while (k < LOG_CATEGORY_COUNT && !(categories[i] && strcmp(categories[i], category_names[k]) == 0))
			++k;
		if (k == LOG_CATEGORY_COUNT) {
			log_error(inst,
			          "fmi2SetDebugLogging: unknown log category \"%s\" (known: logEvents, logStatusWarning, "
			          "logStatusDiscard, logStatusError, logSolver)",
			          categories[i] ? categories[i] : "(null)");
			return fmi2Error;
		}
		mask |= 1u << k;
	}
	// FMI 2.0 (2.1.5): logging on with categories logs those only, with none every category;
	// logging off with none leaves problems reported, with categories switches those off.
	if (loggingOn)
		inst->log_mask = mask;
	else if (nCategories == 0)
		inst->log_mask = LOG_ALWAYS;  // debug output off; problems are still reported
	else
		inst->log_mask &= ~mask;
	return fmi2OK;
}

static void free_instance(instance* inst)
{
	if (!inst)
		return;
	sm_simulation_destroy(inst->sim);
	fmu_table_destroy(&inst->table);
	sm_document_destroy(inst->doc);
	free(inst->text);
	free(inst->parameters);
	free(inst->ports);
	free(inst->held);
	free(inst->port_dirty);
	free(inst->forces);
	free(inst->scratch);
	free(inst->parameter_old);
	free(inst->parameter_new);
	free(inst->name);
	free(inst);
}

// An error of fmi2Instantiate before the instance can log (its own allocation failed): straight
// to the importer's logger, if there is one.
static void log_instantiate_error(const fmi2CallbackFunctions* functions, fmi2String instanceName,
                                  const char* message)
{
	if (functions && functions->logger)
		functions->logger(functions->componentEnvironment, instanceName ? instanceName : "springmass",
		                  fmi2Error, "logStatusError", message);
}

// Reads the resources of the folder dir into the instance: model.json, and parameters.txt when
// it exists. False after logging why not.
static bool read_resources(instance* inst, const char* dir, const char* location)
{
	static const char* const names[2] = {"model.json", FMU_PARAMETERS_RESOURCE};
	char** texts[2] = {&inst->text, &inst->parameters};
	size_t* lengths[2] = {&inst->length, &inst->parameters_length};
	const size_t n = strlen(dir);
	for (int k = 0; k < 2; ++k) {
		char* path = malloc(n + 2 + strlen(names[k]));
		if (!path) {
			log_error(inst, "fmi2Instantiate: out of memory");
			return false;
		}
		sprintf(path, "%s/%s", dir, names[k]);
		const char* problem = NULL;
		*texts[k] = text_file_read(path, lengths[k], &problem);
		if (!*texts[k] && !(k == 1 && errno == ENOENT)) {
			log_error(inst, "fmi2Instantiate: cannot read the %s %s (from resource location \"%s\"): %s",
			          k == 0 ? "model file" : "parameter values", path, location, problem);
			free(path);
			return false;
		}
		free(path);
	}
	return true;
}

// The model file parsed with the parameter values of the FMU applied: what fmi2Instantiate and
// fmi2Reset start from.
static sm_document* parse_document(const instance* inst, sm_error* err)
{
	return fmu_document_parse(inst->text, inst->length, "resources/model.json", inst->parameters,
	                          inst->parameters_length, err);
}

// Whether an instance name names nothing: NULL, empty or only white space (the C locale's, whatever
// the importer's locale). FMI 2.0 (2.1.5): it "must have at least one character that is no white
// space".
static bool blank_name(const char* name)
{
	if (!name)
		return true;
	while (*name && strchr(" \t\n\v\f\r", *name))
		++name;
	return *name == '\0';
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
	(void)visible;
	instance* inst = calloc(1, sizeof *inst);
	if (!inst) {
		log_instantiate_error(functions, instanceName, "fmi2Instantiate: out of memory");
		return NULL;
	}
	inst->logger = functions ? functions->logger : NULL;
	inst->environment = functions ? functions->componentEnvironment : NULL;
	inst->log_mask = LOG_ALWAYS | (loggingOn ? (unsigned)((1u << LOG_CATEGORY_COUNT) - 1u) : 0u);
	inst->state = ST_INSTANTIATED;
	const char* name = blank_name(instanceName) ? "springmass" : instanceName;
	inst->name = malloc(strlen(name) + 1);
	if (!inst->name) {
		free(inst);
		log_instantiate_error(functions, instanceName, "fmi2Instantiate: out of memory");
		return NULL;
	}
	strcpy(inst->name, name);

	if (blank_name(instanceName)) {
		log_error(inst,
		          "fmi2Instantiate: missing instance name (it needs a character that is no white space)");
		goto fail;
	}
	if (fmuType != fmi2CoSimulation) {
		log_error(inst, "fmi2Instantiate: this FMU supports Co-Simulation only (fmuType = %d)", (int)fmuType);
		goto fail;
	}
	if (!fmuGUID) {
		log_error(inst, "fmi2Instantiate: missing GUID");
		goto fail;
	}
	// An empty location names no folder: joined with the file names it would read the root's.
	if (!fmuResourceLocation || !fmuResourceLocation[0]) {
		log_error(
		    inst,
		    "fmi2Instantiate: missing resource location (the FMU's resources folder holds the model file)");
		goto fail;
	}
	bool out_of_memory = false;
	char* dir = resource_path(fmuResourceLocation, &out_of_memory);
	if (out_of_memory) {
		log_error(inst, "fmi2Instantiate: out of memory");
		goto fail;
	}
	if (!dir) {
		log_error(
		    inst,
		    "fmi2Instantiate: resource location \"%s\" is not a local file URI (file:///dir, file:/dir, "
		    "file://localhost/dir or a path, without an escaped NUL)",
		    fmuResourceLocation);
		goto fail;
	}
	const bool read = read_resources(inst, dir, fmuResourceLocation);
	free(dir);
	if (!read)
		goto fail;

	char guid[40];
	fmu_package_guid(inst->text, inst->length, inst->parameters, inst->parameters_length, guid);
	if (strcmp(guid, fmuGUID) != 0) {
		log_error(
		    inst,
		    "fmi2Instantiate: GUID %s does not match the model file resources/model.json%s, whose GUID is %s: "
		    "the importer passed another FMU's GUID, or the resources were changed after packaging",
		    fmuGUID, inst->parameters ? " with its parameter values resources/" FMU_PARAMETERS_RESOURCE : "",
		    guid);
		goto fail;
	}
	sm_error err = {SM_OK, ""};
	inst->doc = parse_document(inst, &err);
	if (!inst->doc) {
		log_error(inst, "fmi2Instantiate: %s", err.message);
		goto fail;
	}
	if (fmu_table_create(inst->doc, inst->text, inst->length, inst->parameters, inst->parameters_length,
	                     &inst->table, &err) != SM_OK) {
		log_error(inst, "fmi2Instantiate: %s", err.message);
		goto fail;
	}
	inst->particle_count = sm_document_particle_count(inst->doc);
	inst->spring_count = sm_document_spring_count(inst->doc);
	inst->port_count = sm_document_port_count(inst->doc);
	size_t np = inst->port_count > 0 ? (size_t)inst->port_count : 1;
	size_t n3 = 3 * (size_t)(inst->particle_count > 0 ? inst->particle_count : 1);
	inst->ports = calloc(np, sizeof *inst->ports);
	inst->held = calloc(np, sizeof *inst->held);
	inst->port_dirty = calloc(np, sizeof *inst->port_dirty);
	inst->forces = calloc(n3, sizeof *inst->forces);
	inst->scratch = calloc(5 * n3, sizeof *inst->scratch);
	inst->parameter_old = calloc((size_t)sm_document_parameter_count(inst->doc) + 1, sizeof(double));
	inst->parameter_new = calloc((size_t)sm_document_parameter_count(inst->doc) + 1, sizeof(double));
	if (!inst->ports || !inst->held || !inst->port_dirty || !inst->forces || !inst->scratch ||
	    !inst->parameter_old || !inst->parameter_new) {
		log_error(inst, "fmi2Instantiate: out of memory");
		goto fail;
	}
	for (int32_t p = 0; p < inst->port_count; ++p)
		inst->ports[p] = sm_document_port(inst->doc, p);
	load_start_values(inst);
	return inst;

fail:
	free_instance(inst);
	return NULL;
}

void fmi2FreeInstance(fmi2Component c)
{
	free_instance(c);
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0: initialisation, termination, reset
// ---------------------------------------------------------------------------------------------

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetupExperiment", ST_INSTANTIATED))
		return fmi2Error;
	// The times in the digits that read back: a start a fraction of a second after the stop at a Unix
	// time (1.7e9 s) would otherwise read as equal to it. Without a stop time there is none to name.
	if (!isfinite(startTime) && !stopTimeDefined) {
		log_error(inst, "fmi2SetupExperiment: start time %s must be finite", fmu_number_text(startTime).text);
		return fmi2Error;
	}
	if (!isfinite(startTime) || (stopTimeDefined && (!isfinite(stopTime) || stopTime < startTime))) {
		log_error(inst,
		          "fmi2SetupExperiment: start time %s and stop time %s must be finite with start <= stop",
		          fmu_number_text(startTime).text, fmu_number_text(stopTime).text);
		return fmi2Error;
	}
	if (toleranceDefined && !(tolerance > 0.0 && tolerance < 1.0)) {
		log_error(inst, "fmi2SetupExperiment: tolerance %g must lie in (0, 1)", tolerance);
		return fmi2Error;
	}
	// It becomes CVODE's relative tolerance, which cannot be met below the machine epsilon.
	if (toleranceDefined && !(tolerance >= SM_MIN_RELATIVE_TOLERANCE)) {
		log_error(inst,
		          "fmi2SetupExperiment: tolerance %s must be at least %s, the machine epsilon (CVODE cannot "
		          "meet a smaller relative tolerance)",
		          fmu_number_text(tolerance).text, fmu_number_text(SM_MIN_RELATIVE_TOLERANCE).text);
		return fmi2Error;
	}
	// The experiment's tolerance, or without one the file's (an earlier call's does not stay).
	if (!inst->rtol_set)
		inst->solver.relative_tolerance =
		    toleranceDefined ? tolerance : sm_document_get_settings(inst->doc).solver.relative_tolerance;
	inst->start_time = startTime;
	inst->time = startTime;
	inst->stop_time_defined = stopTimeDefined;
	inst->stop_time = stopTime;
	inst->sim_dirty = true;
	return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2EnterInitializationMode", ST_INSTANTIATED))
		return fmi2Error;
	inst->state = ST_INITIALIZATION;
	inst->time = inst->start_time;
	return fmi2OK;
}

// fmi2OK, or fmi2Warning, logged, when the absolute tolerances the instance simulates with are
// coarse for its model (sm_tolerances_coarse), as `springmass fmu` warns at packaging. The
// tolerances are fixed from here on; the model's scales are judged as they are now: tunable
// parameters (stiffness, masses, rest lengths) set between steps may move them, unchecked.
static fmi2Status coarse_tolerance_warning(instance* inst, const char* function)
{
	sm_motion_scales scales;
	if (sm_model_motion_scales(sm_simulation_model(inst->sim), &scales) != SM_OK ||
	    !sm_tolerances_coarse(&inst->solver, &scales))
		return fmi2OK;
	fmu_logf(inst, fmi2Warning, LOG_WARNING,
	         "%s: the absolute tolerances, solver.atol_position = %g m and solver.atol_velocity = %g m/s, "
	         "are coarse for this model: its shortest spring is %.3g m and moves at up to %.3g m/s at its "
	         "highest frequency, so its motion is resolved only to them (suited to it: about 1e-8 of these "
	         "scales, %.1g m and %.1g m/s, set during initialisation)",
	         function, inst->solver.absolute_tolerance_position, inst->solver.absolute_tolerance_velocity,
	         scales.length, scales.speed, 1e-8 * scales.length, 1e-8 * scales.speed);
	return fmi2Warning;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2ExitInitializationMode", ST_INITIALIZATION))
		return fmi2Error;
	if (fmu_ensure_simulation(inst, "fmi2ExitInitializationMode") != fmi2OK) {
		inst->state = ST_ERROR;
		return fmi2Error;
	}
	inst->last_successful_time = inst->time;
	inst->state = ST_STEP_COMPLETE;
	return coarse_tolerance_warning(inst, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2Terminate", ST_STEP_COMPLETE | ST_STEP_FAILED))
		return fmi2Error;
	inst->state = ST_TERMINATED;
	return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2Reset", ST_ANY))
		return fmi2Error;
	sm_error err = {SM_OK, ""};
	sm_document* doc = parse_document(inst, &err);
	if (!doc) {
		log_error(inst, "fmi2Reset: %s", err.message);
		inst->state = ST_ERROR;
		return fmi2Error;
	}
	sm_document_destroy(inst->doc);
	inst->doc = doc;
	for (int32_t p = 0; p < inst->port_count; ++p)
		inst->ports[p] = sm_document_port(inst->doc, p);
	sm_simulation_destroy(inst->sim);
	inst->sim = NULL;
	inst->sim_dirty = true;
	inst->start_time = 0.0;
	inst->time = 0.0;
	inst->last_successful_time = 0.0;
	inst->stop_time_defined = false;
	inst->dissipated_offset = 0.0;
	inst->work_origin = 0.0;
	inst->work_offset = 0.0;
	inst->breaks_logged = 0;
	fmu_forget_derived_values(inst);
	load_start_values(inst);
	inst->state = ST_INSTANTIATED;
	return fmi2OK;
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0: getting and setting values
// ---------------------------------------------------------------------------------------------

// The energies, evaluated once per state: the three energy outputs share one pass over the
// particles and springs, and the end of a step's check of the outputs and the master's reads after
// it share that pass too.
static const sm_energies* current_energies(instance* inst)
{
	if (!inst->energies_valid) {
		inst->energies = sm_simulation_energies(inst->sim);
		inst->energies_valid = true;
	}
	return &inst->energies;
}

static double real_value(instance* inst, const fmu_variable* v)
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
		return current_forces(inst)[3 * inst->ports[v->index].particle + v->component];
	case FMU_SRC_PARTICLE_POSITION: return x[3 * v->index + v->component];
	case FMU_SRC_PARTICLE_VELOCITY: return u[3 * v->index + v->component];
	case FMU_SRC_ENERGY_KINETIC: return current_energies(inst)->kinetic;
	case FMU_SRC_ENERGY_ELASTIC: return current_energies(inst)->elastic;
	case FMU_SRC_ENERGY_GRAVITY: return current_energies(inst)->gravity;
	case FMU_SRC_ENERGY_DISSIPATED: return fmu_dissipated_energy(inst);
	case FMU_SRC_ENERGY_INPUT: return fmu_input_work(inst);
	default: return NAN;
	}
}

// fmi2OK, or fmi2Warning, logged, when a value read (`what`: "" or "the derivative of ") of
// `overflowing` is beyond the range of a double.
static fmi2Status overflow_warning(instance* inst, const char* function, const char* what,
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
	if (!fmu_allowed(inst, "fmi2GetReal", ST_RUNNING) || !check_arrays(inst, "fmi2GetReal", vr, nvr, value))
		return fmi2Error;
	const fmu_variable* overflowing = NULL;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2GetReal", vr[i], FMU_REAL);
		if (!v)
			return fmi2Error;
		if (needs_simulation(v) && (!inst->sim || inst->sim_dirty || inst->state == ST_INITIALIZATION)) {
			if (fmu_ensure_simulation(inst, "fmi2GetReal") != fmi2OK)
				return fmi2Error;
		} else if (needs_simulation(v) && apply_inputs(inst, "fmi2GetReal") != fmi2OK) {
			return fmi2Error;
		}
		value[i] = real_value(inst, v);
		if (!isfinite(value[i]) && overflowing == NULL)
			overflowing = v;
	}
	// A finite state whose outputs overflow (an input far beyond the model's scale, such as a
	// motion port at 1e300 m, whose spring's squared length does): the values are given, as they
	// are, with fmi2Warning and the first such variable named; a step from here is discarded.
	return overflow_warning(inst, "fmi2GetReal", "", overflowing);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetInteger", ST_RUNNING) ||
	    !check_arrays(inst, "fmi2GetInteger", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2GetInteger", vr[i], FMU_INTEGER);
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
	    !check_arrays(inst, "fmi2GetBoolean", vr, nvr, value))
		return fmi2Error;
	if (nvr > 0) {
		log_error(inst, "fmi2GetBoolean: value reference %u: this FMU has no Boolean variables",
		          (unsigned)vr[0]);
		return fmi2Error;
	}
	return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetString", ST_RUNNING) ||
	    !check_arrays(inst, "fmi2GetString", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2GetString", vr[i], FMU_STRING);
		if (!v)
			return fmi2Error;
		switch (v->source) {
		case FMU_SRC_SOLVER_METHOD: value[i] = sm_method_name(inst->solver.method); break;
		case FMU_SRC_SOLVER_LINEAR_SOLVER: value[i] = sm_linear_solver_name(inst->solver.solver); break;
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
	    !check_arrays(inst, "fmi2SetReal", vr, nvr, value))
		return fmi2Error;
	// A rejected call changes nothing: every value is checked first, then the model-file
	// parameters are set together (and put back if the model rejects them), then the rest.
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2SetReal", vr[i], FMU_REAL);
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
	    !check_arrays(inst, "fmi2SetInteger", vr, nvr, value))
		return fmi2Error;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2SetInteger", vr[i], FMU_INTEGER);
		if (!v || !settable(inst, "fmi2SetInteger", v))
			return fmi2Error;
		if (value[i] < 1) {
			log_error(inst, "fmi2SetInteger: %s = %d rejected: must be >= 1", v->name, (int)value[i]);
			return fmi2Error;
		}
	}
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2SetInteger", vr[i], FMU_INTEGER);
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
	    !check_arrays(inst, "fmi2SetBoolean", vr, nvr, value))
		return fmi2Error;
	if (nvr > 0) {
		log_error(inst, "fmi2SetBoolean: value reference %u: this FMU has no Boolean variables",
		          (unsigned)vr[0]);
		return fmi2Error;
	}
	return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetString", ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE) ||
	    !check_arrays(inst, "fmi2SetString", vr, nvr, value))
		return fmi2Error;
	sm_simulation_def solver = inst->solver;
	for (size_t i = 0; i < nvr; ++i) {
		const fmu_variable* v = lookup(inst, "fmi2SetString", vr[i], FMU_STRING);
		if (!v || !settable(inst, "fmi2SetString", v))
			return fmi2Error;
		int bad = 0;
		if (!value[i]) {
			bad = 1;
		} else if (v->source == FMU_SRC_SOLVER_METHOD) {
			bad = sm_method_from_name(value[i], &solver.method) != SM_OK;
		} else if (v->source == FMU_SRC_SOLVER_LINEAR_SOLVER) {
			bad = sm_linear_solver_from_name(value[i], &solver.solver) != SM_OK;
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

// ---------------------------------------------------------------------------------------------
// FMI 2.0: directional derivatives of outputs with respect to inputs at the current
// communication point (the direct feed-through a master needs). With dx and dv the seeds of the
// motion ports' prescribed positions and velocities and g the seeds of the force inputs:
//   d(force on a driven particle)  = (df/dx dx + df/dv dv)_p + g_p   (analytic Jacobian product)
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
	                                    : apply_inputs(inst, fn) != fmi2OK)
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
			int32_t particle = inst->ports[v->index].particle;
			result = state_output_change(inst, v, dx, dv, work, &evaluated);
			for (size_t j = 0; j < nKnown; ++j) {
				const fmu_variable* w = &inst->table.variables[vKnown_ref[j]];
				if (w->source == FMU_SRC_PORT_FORCE && inst->ports[w->index].particle == particle &&
				    w->component == v->component)
					result += dvKnown[j];
			}
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
// FMI 2.0 Co-Simulation: stepping and status
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
	    !check_arrays(inst, fn, vr, nvr, value) || !check_arrays(inst, fn, vr, nvr, order))
		return fmi2Error;
	for (size_t k = 0; k < nvr; ++k) {
		const fmu_variable* v = lookup(inst, fn, vr[k], FMU_REAL);
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
		const fmu_variable* v = lookup(inst, fn, vr[k], FMU_REAL);
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
		const double* f = current_forces(inst);
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
	return overflow_warning(inst, fn, "the derivative of ", overflowing);
}

// Whether every output is finite, checked over a superset of their values: every particle's
// position and velocity, where there are motion ports (whose reaction forces are the force
// outputs) the forces on every particle, and the energies. False only sends end_step on to read
// each output, to name the first that is not finite. Reading each through the table at every
// step took half of a communication step that CVODE interpolates (the bundled two-mass chain at
// 1e-4 s with a stop time: 2500 of 5300 instructions, for 20 outputs among 62 variables); the
// check takes 980, 700 of them the forces and the energies.
static bool outputs_finite(instance* inst)
{
	const size_t n3 = 3 * (size_t)inst->particle_count;
	const double* x = sm_simulation_positions(inst->sim);
	const double* u = sm_simulation_velocities(inst->sim);
	bool motion_ports = false;
	for (int32_t p = 0; p < inst->port_count; ++p)
		motion_ports = motion_ports || inst->ports[p].kind == SM_PORT_MOTION;
	const double* f = motion_ports ? current_forces(inst) : NULL;
	// 0 x is 0 for a finite x and NaN for an infinite or NaN one.
	double zero = 0.0;
	for (size_t i = 0; i < n3; ++i)
		zero += 0.0 * x[i] + 0.0 * u[i] + (f ? 0.0 * f[i] : 0.0);
	const sm_energies* e = current_energies(inst);
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
		if (v->type == FMU_REAL && v->causality == FMU_OUTPUT && !isfinite(real_value(inst, v)))
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
	if (st == SM_ERROR_STEP_LIMIT)
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
		if (apply_inputs(inst, "fmi2DoStep") != fmi2OK)
			return fmi2Error;
		if (logging(inst, LOG_SOLVER))
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
	if (apply_inputs(inst, "fmi2DoStep") != fmi2OK)
		return fmi2Error;
	// The solver's counters for the log only: reading them costs a fifteenth of a step that CVODE
	// interpolates.
	const bool log_solver = logging(inst, LOG_SOLVER);
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
		if (logging(inst, LOG_EVENTS))
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
	(void)value;
	if (!fmu_allowed(inst, "fmi2GetIntegerStatus", ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED))
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

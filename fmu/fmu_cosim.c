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
// This file holds the instance's life: logging, the resources, the model and the simulation,
// instantiation, initialisation, termination and reset. The other entry points are beside it:
// getting and setting values in fmu_values.c, directional, input and output derivatives in
// fmu_derivatives.c, fmi2DoStep and the status functions in fmu_step.c, the FMU state
// (fmi2GetFMUstate to fmi2DeSerializeFMUstate) in fmu_state.c. What they share is declared in
// fmu_instance.h.
#define _POSIX_C_SOURCE 200809L
#include "fmu_instance.h"
#include "text_file.h"

#include <ctype.h>
#include <errno.h>
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
bool fmu_logging(const instance* inst, unsigned category)
{
	return inst && inst->logger && (inst->log_mask & category);
}

void fmu_logf(instance* inst, fmi2Status status, unsigned category, const char* fmt, ...)
{
	if (!fmu_logging(inst, category))
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
	// solver.input_changes (the model file's "input_changes", "restart" unless it says "keep"): an
	// input set is a jump of the right-hand side when its value changes (a force switched on, a drive
	// that moves off its extrapolated path; the simulation compares), where CVODE restarts by
	// default if its high-order history cannot carry the jump within the tolerances (docs/fmu.md,
	// "Measured: when to restart CVODE"). Inputs set to what they were keep the history.
	inst->solver = settings.solver;
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
	// All at once: one at a time, each numbered the free particles again, a time in proportion to
	// the motion ports times the particles at every build (a tunable parameter set builds anew).
	st = sm_set_motion_of(model, inst->driven, inst->driven_count, SM_PARTICLE_DRIVEN);
	if (st != SM_OK) {
		log_error(inst, "%s: cannot drive the particles of the motion ports: %s", function,
		          sm_model_last_error(model));
		sm_model_destroy(model);
		return st;
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
fmi2Status fmu_apply_inputs(instance* inst, const char* function)
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
		return fmu_apply_inputs(inst, function);
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

const double* fmu_current_forces(instance* inst)
{
	if (!inst->forces_valid) {
		sm_simulation_forces(inst->sim, inst->forces);
		inst->forces_valid = true;
	}
	return inst->forces;
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
	free(inst->driven);
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
	inst->driven = calloc(np, sizeof *inst->driven);
	inst->held = calloc(np, sizeof *inst->held);
	inst->port_dirty = calloc(np, sizeof *inst->port_dirty);
	inst->forces = calloc(n3, sizeof *inst->forces);
	inst->scratch = calloc(5 * n3, sizeof *inst->scratch);
	inst->parameter_old = calloc((size_t)sm_document_parameter_count(inst->doc) + 1, sizeof(double));
	inst->parameter_new = calloc((size_t)sm_document_parameter_count(inst->doc) + 1, sizeof(double));
	if (!inst->ports || !inst->driven || !inst->held || !inst->port_dirty || !inst->forces ||
	    !inst->scratch || !inst->parameter_old || !inst->parameter_new) {
		log_error(inst, "fmi2Instantiate: out of memory");
		goto fail;
	}
	for (int32_t p = 0; p < inst->port_count; ++p) {
		inst->ports[p] = sm_document_port(inst->doc, p);
		if (inst->ports[p].kind == SM_PORT_MOTION)
			inst->driven[inst->driven_count++] = inst->ports[p].particle;
	}
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
// coarse for its model (sm_tolerances_coarse), or the velocities' too tight for the round-off of
// its stiffest spring's force (sm_tolerances_tight), as `springmass fmu` warns at packaging. The
// tolerances are fixed from here on; the model's scales are judged as they are now: tunable
// parameters (stiffness, masses, rest lengths) set between steps may move them, unchecked.
static fmi2Status tolerance_warning(instance* inst, const char* function)
{
	const sm_model* model = sm_simulation_model(inst->sim);
	sm_round_off round_off;
	if (sm_model_round_off(model, &round_off) == SM_OK && sm_tolerances_tight(&inst->solver, &round_off)) {
		fmu_logf(
		    inst, fmi2Warning, LOG_WARNING,
		    "%s: the absolute tolerance of velocities, solver.atol_velocity = %g m/s, is too tight for the "
		    "round-off of spring %d, %g N/m: rounding its force moves its ends' velocities by up to %.2g m/s "
		    "in a step, and CVODE's steps fail over and over below a tenth of that (it may stop at "
		    "solver.max_steps; %.2g m/s or more, set during initialisation)",
		    function, inst->solver.absolute_tolerance_velocity, (int)round_off.spring, round_off.stiffness,
		    round_off.velocity, SM_TIGHT_TOLERANCE * round_off.velocity);
		return fmi2Warning;
	}
	sm_motion_scales scales;
	if (sm_model_motion_scales(model, &scales) != SM_OK || !sm_tolerances_coarse(&inst->solver, &scales))
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
	return tolerance_warning(inst, "fmi2ExitInitializationMode");
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

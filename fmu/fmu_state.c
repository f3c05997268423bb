// springmass FMU: the FMU state of FMI 2.0. fmi2GetFMUstate and fmi2SetFMUstate save and restore
// an instance's state, fmi2FreeFMUstate frees one, and fmi2SerializedFMUstateSize,
// fmi2SerializeFMUstate and fmi2DeSerializeFMUstate turn one into bytes and back: the saved
// state's layout, its checksum and the checks a state must pass before any of it is used.
#include "fmu_instance.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// FMI 2.0: FMU state. The saved state is the model's state, not solver memory: time, every
// particle's position and velocity, which springs are broken, the inputs, the parameters and
// settings, the dissipated energy and the inputs' work. Not the stop time: that is the
// experiment's, which the instance restoring a state was given by its own fmi2SetupExperiment
// (FMI 2.0, 2.1.6), and a state may start a longer run than the one that saved it. Restoring creates the
// simulation from it, so CVODE starts afresh, and every restore of a state continues alike (bit for bit, in
// this or another process). Getting a state only copies (FMI 2.0, 2.1.8): the running instance keeps CVODE's
// history and goes on as if no state had been saved.
// ---------------------------------------------------------------------------------------------

#define STATE_MAGIC "SMFMUST9"

// Serialised layout: magic[8], guid[40], then int64 and double fields in the order below, then
// x[3n], v[3n], enabled[m] (as doubles 0/1), parameters[np], held ports[PORT_DOUBLES nports], pending
// ports[nports] (inputs set since the last step, as doubles 0/1: a state saved between setting
// inputs and fmi2DoStep steps with them when restored). The checksum
// is a 64-bit FNV-1a hash of all other bytes: a serialised state that was truncated, extended or
// changed in transit is refused before anything of it is used.
enum {
	I_SIZE,
	I_CHECKSUM,
	I_STATE,
	I_PARTICLES,
	I_SPRINGS,
	I_PARAMETERS,
	I_PORTS,
	I_HAS_SIM,
	I_METHOD,
	I_LINEAR_SOLVER,
	I_JACOBIAN,
	I_MAX_STEPS,
	I_THREADS,
	I_RTOL_SET,
	I_RESTART_ON_INPUT_CHANGE,
	I_STABILITY_LIMIT_DETECTION,
	I_COUNT
};
enum {
	D_TIME,
	D_START,
	D_LAST_SUCCESSFUL,
	D_DISSIPATED,
	D_RTOL,
	D_ATOL_POSITION,
	D_ATOL_VELOCITY,
	D_MAX_STEP,
	D_INPUT_WORK,
	D_COUNT
};
#define HEADER_BYTES (8 + 40 + 8 * I_COUNT + 8 * D_COUNT)
#define CHECKSUM_OFFSET (48 + 8 * I_CHECKSUM)

// The checksum guards bytes that leave the FMU. A state that fmi2GetFMUstate saved is written
// without it (checksummed false): a master that saves the state before every step, to roll a
// rejected one back, would otherwise hash all of it, a byte at a time, at every step, which added
// 60 % to the time of a step of 1e-4 s of the bundled two-mass chain. It is written when the bytes
// first leave (fmi2SerializeFMUstate) or are restored (fmi2SetFMUstate, which checks it as for any
// state); a state read back from bytes comes with it.
typedef struct saved_state {
	size_t size;
	unsigned char* bytes;
	bool checksummed;
} saved_state;

static size_t state_size(const instance* inst)
{
	size_t n = (size_t)inst->particle_count, m = (size_t)inst->spring_count;
	size_t np = (size_t)sm_document_parameter_count(inst->doc), nports = (size_t)inst->port_count;
	return HEADER_BYTES + 8 * (6 * n + m + np + (PORT_DOUBLES + 1) * nports);
}

static void put_i(unsigned char* b, int k, int64_t v)
{
	memcpy(b + 48 + 8 * k, &v, 8);
}
static int64_t get_i(const unsigned char* b, int k)
{
	int64_t v;
	memcpy(&v, b + 48 + 8 * k, 8);
	return v;
}
static void put_d(unsigned char* b, int k, double v)
{
	memcpy(b + 48 + 8 * I_COUNT + 8 * k, &v, 8);
}
static double get_d(const unsigned char* b, int k)
{
	double v;
	memcpy(&v, b + 48 + 8 * I_COUNT + 8 * k, 8);
	return v;
}

// 64-bit FNV-1a of a state's bytes except its checksum field (size >= HEADER_BYTES).
static int64_t state_checksum(const unsigned char* b, size_t size)
{
	uint64_t hash = 0xcbf29ce484222325u;  // FNV-64 offset basis
	for (size_t i = 0; i < size; ++i) {
		if (i < CHECKSUM_OFFSET || i >= CHECKSUM_OFFSET + 8)
			hash = (hash ^ b[i]) * 0x100000001b3u;  // FNV-64 prime
	}
	int64_t v;
	memcpy(&v, &hash, 8);
	return v;
}

// Writes its checksum into a state saved without one.
static void write_checksum(saved_state* s)
{
	if (!s->checksummed) {
		put_i(s->bytes, I_CHECKSUM, state_checksum(s->bytes, s->size));
		s->checksummed = true;
	}
}

// Saves the instance's state into `reuse` when it is a state of the same size (fmi2GetFMUstate
// given one to overwrite, as a master saving before every step does), or into a new one; NULL
// when memory runs out. Every byte but the checksum's is written.
static saved_state* save_state(instance* inst, saved_state* reuse)
{
	const size_t size = state_size(inst);
	saved_state* s = reuse != NULL && reuse->size == size ? reuse : malloc(sizeof *s);
	if (!s)
		return NULL;
	if (s != reuse) {
		s->size = size;
		s->bytes = calloc(1, size);
		if (!s->bytes) {
			free(s);
			return NULL;
		}
	}
	s->checksummed = false;
	unsigned char* b = s->bytes;
	memcpy(b, STATE_MAGIC, 8);
	memcpy(b + 8, inst->table.guid, 40);
	int32_t n = inst->particle_count, m = inst->spring_count, np = sm_document_parameter_count(inst->doc);
	bool has_sim = inst->sim && !inst->sim_dirty && !(inst->state & ST_INSTANTIATED);
	put_i(b, I_SIZE, (int64_t)s->size);
	put_i(b, I_STATE, inst->state);
	put_i(b, I_PARTICLES, n);
	put_i(b, I_SPRINGS, m);
	put_i(b, I_PARAMETERS, np);
	put_i(b, I_PORTS, inst->port_count);
	put_i(b, I_HAS_SIM, has_sim);
	put_i(b, I_METHOD, inst->solver.method);
	put_i(b, I_LINEAR_SOLVER, inst->solver.solver);
	put_i(b, I_JACOBIAN, inst->solver.jacobian);
	put_i(b, I_MAX_STEPS, inst->solver.max_steps);
	put_i(b, I_THREADS, inst->solver.threads);
	put_i(b, I_RTOL_SET, inst->rtol_set);
	put_i(b, I_RESTART_ON_INPUT_CHANGE, inst->solver.restart_on_input_change);
	put_i(b, I_STABILITY_LIMIT_DETECTION, inst->solver.stability_limit_detection);
	put_d(b, D_TIME, inst->time);
	put_d(b, D_START, inst->start_time);
	put_d(b, D_LAST_SUCCESSFUL, inst->last_successful_time);
	put_d(b, D_DISSIPATED, has_sim ? fmu_dissipated_energy(inst) : 0.0);
	put_d(b, D_RTOL, inst->solver.relative_tolerance);
	put_d(b, D_ATOL_POSITION, inst->solver.absolute_tolerance_position);
	put_d(b, D_ATOL_VELOCITY, inst->solver.absolute_tolerance_velocity);
	put_d(b, D_MAX_STEP, inst->solver.max_step);
	put_d(b, D_INPUT_WORK, has_sim ? fmu_input_work(inst) : 0.0);
	double* d = (double*)(void*)(b + HEADER_BYTES);  // HEADER_BYTES is a multiple of 8
	if (has_sim) {
		memcpy(d, sm_simulation_positions(inst->sim), 3 * (size_t)n * sizeof(double));
		memcpy(d + 3 * n, sm_simulation_velocities(inst->sim), 3 * (size_t)n * sizeof(double));
		const sm_model* model = sm_simulation_model(inst->sim);
		for (int32_t k = 0; k < m; ++k)
			d[6 * n + k] = sm_model_spring_enabled(model, k) ? 1.0 : 0.0;
	} else {
		memset(d, 0, 6 * (size_t)n * sizeof(double));
		for (int32_t k = 0; k < m; ++k)
			d[6 * n + k] = 1.0;
	}
	for (int32_t k = 0; k < np; ++k)
		d[6 * n + m + k] = sm_document_parameter_value(inst->doc, k);
	memcpy(d + 6 * n + m + np, inst->held, (size_t)inst->port_count * sizeof(port_values));
	for (int32_t p = 0; p < inst->port_count; ++p)
		d[6 * n + m + np + PORT_DOUBLES * (size_t)inst->port_count + p] = inst->port_dirty[p] ? 1.0 : 0.0;
	put_i(b, I_CHECKSUM, 0);
	return s;
}

// The k-th double of the values after the header. The bytes of fmi2DeSerializeFMUstate are the
// caller's, at any address: they are read without assuming the alignment of a double.
static double value_at(const unsigned char* b, size_t k)
{
	double v;
	memcpy(&v, b + HEADER_BYTES + 8 * k, 8);
	return v;
}

static bool all_finite(const unsigned char* b, size_t first, size_t count)
{
	for (size_t k = first; k < first + count; ++k)
		if (!isfinite(value_at(b, k)))
			return false;
	return true;
}

static bool all_flags(const unsigned char* b, size_t first, size_t count)
{
	for (size_t k = first; k < first + count; ++k)
		if (value_at(b, k) != 0.0 && value_at(b, k) != 1.0)
			return false;
	return true;
}

// Checks that bytes are a state of this model with values the instance can take; logs and
// returns false otherwise. The checksum catches damage; the checks after it, states written by
// something else than save_state.
static bool valid_state(instance* inst, const char* function, const unsigned char* b, size_t size)
{
	// The magic's last character is the layout's version: a state of another version is named as
	// such, since its fields would be read at the wrong places.
	if (size >= 8 && memcmp(b, STATE_MAGIC, 7) == 0 && b[7] != (unsigned char)STATE_MAGIC[7]) {
		log_error(inst,
		          "%s: a state of another springmass version (layout %c, this FMU reads %c): save it again "
		          "with this FMU",
		          function, b[7] >= 0x20 && b[7] < 0x7f ? (char)b[7] : '?', STATE_MAGIC[7]);
		return false;
	}
	if (size < HEADER_BYTES || memcmp(b, STATE_MAGIC, 8) != 0) {
		log_error(inst, "%s: not a springmass FMU state", function);
		return false;
	}
	if (memcmp(b + 8, inst->table.guid, 40) != 0) {
		// The GUID as written (up to its NUL), printable characters only: the bytes may be anything.
		char guid[40];
		int length = 0;
		for (; length < 39 && b[8 + length] != '\0'; ++length)
			guid[length] = b[8 + length] >= 0x20 && b[8 + length] < 0x7f ? (char)b[8 + length] : '?';
		guid[length] = '\0';
		log_error(inst, "%s: the state belongs to another model (GUID %s, this FMU's is %s)", function, guid,
		          inst->table.guid);
		return false;
	}
	if (get_i(b, I_SIZE) != (int64_t)size || size != state_size(inst) ||
	    get_i(b, I_PARTICLES) != inst->particle_count || get_i(b, I_SPRINGS) != inst->spring_count ||
	    get_i(b, I_PORTS) != inst->port_count ||
	    get_i(b, I_PARAMETERS) != sm_document_parameter_count(inst->doc)) {
		log_error(inst,
		          "%s: the state's size or counts do not match this model (%zu bytes, this model's take %zu)",
		          function, size, state_size(inst));
		return false;
	}
	if (get_i(b, I_CHECKSUM) != state_checksum(b, size)) {
		log_error(inst, "%s: the state's checksum does not match its bytes: it was damaged", function);
		return false;
	}
	size_t n3 = 3 * (size_t)inst->particle_count, m = (size_t)inst->spring_count;
	size_t np = (size_t)sm_document_parameter_count(inst->doc), nports = (size_t)inst->port_count;
	int64_t state = get_i(b, I_STATE), has_sim = get_i(b, I_HAS_SIM);
	// A state saved in the error state may or may not hold a simulation (the error may have been
	// creating it); it is never restored (fmi2SetFMUstate), only serialised and read back.
	bool ok = ((state == ST_INSTANTIATED || state == ST_INITIALIZATION || state == ST_STEP_COMPLETE ||
	            state == ST_STEP_FAILED || state == ST_TERMINATED) &&
	           has_sim == (state != ST_INSTANTIATED)) ||
	          (state == ST_ERROR && (has_sim & ~1) == 0);
	ok = ok && get_i(b, I_METHOD) >= 0 && get_i(b, I_METHOD) <= SM_METHOD_ADAMS &&
	     get_i(b, I_LINEAR_SOLVER) >= 0 && get_i(b, I_LINEAR_SOLVER) < SM_SOLVER_COUNT &&
	     get_i(b, I_JACOBIAN) >= 0 && get_i(b, I_JACOBIAN) <= SM_JACOBIAN_DEFINITE &&
	     get_i(b, I_MAX_STEPS) >= 1 && get_i(b, I_MAX_STEPS) <= INT32_MAX && get_i(b, I_THREADS) >= 1 &&
	     get_i(b, I_THREADS) <= INT32_MAX && (get_i(b, I_RTOL_SET) & ~1) == 0 &&
	     (get_i(b, I_RESTART_ON_INPUT_CHANGE) & ~1) == 0 && (get_i(b, I_STABILITY_LIMIT_DETECTION) & ~1) == 0;
	double rtol = get_d(b, D_RTOL), atol_x = get_d(b, D_ATOL_POSITION), atol_v = get_d(b, D_ATOL_VELOCITY);
	double max_step = get_d(b, D_MAX_STEP);
	// The tolerances as fmi2SetReal takes them: the relative one at least SM_MIN_RELATIVE_TOLERANCE
	// and below 1, the absolute ones at least SM_MIN_ABSOLUTE_TOLERANCE.
	ok = ok && rtol >= SM_MIN_RELATIVE_TOLERANCE && rtol < 1.0 && atol_x >= SM_MIN_ABSOLUTE_TOLERANCE &&
	     isfinite(atol_x) && atol_v >= SM_MIN_ABSOLUTE_TOLERANCE && isfinite(atol_v) && max_step >= 0.0 &&
	     isfinite(max_step);
	ok = ok && isfinite(get_d(b, D_TIME)) && isfinite(get_d(b, D_START)) &&
	     isfinite(get_d(b, D_LAST_SUCCESSFUL));
	// Time only runs forward from the experiment's start: t >= start in every state; from the
	// end of initialisation on, the last successful time lies between them (fmi2DoStep sets it to
	// where the step got, which is t). The error state may come before the end of initialisation.
	const double time = get_d(b, D_TIME), start = get_d(b, D_START), last = get_d(b, D_LAST_SUCCESSFUL);
	ok = ok && time >= start &&
	     (state == ST_INSTANTIATED || state == ST_INITIALIZATION || state == ST_ERROR ||
	      (last >= start && last <= time));
	ok = ok && all_finite(b, 0, 2 * n3) && all_finite(b, 2 * n3 + m, np + PORT_DOUBLES * nports);
	ok = ok && all_flags(b, 2 * n3, m) && all_flags(b, 2 * n3 + m + np + PORT_DOUBLES * nports, nports);
	if (!ok) {
		log_error(inst,
		          "%s: the state holds values out of range (FMU state, solver settings, times, positions, "
		          "velocities, parameters or inputs)",
		          function);
		return false;
	}
	// Dissipated energy is finite and non-negative by physics, and save_state writes it so, round-off
	// included (fmu_dissipated_energy): a value below 0, however little, or not finite comes from
	// no state of this FMU, and energy.dissipated would read it from then on.
	const double dissipated = get_d(b, D_DISSIPATED);
	if (!(isfinite(dissipated) && dissipated >= 0.0)) {
		log_error(inst, "%s: the state's dissipated energy %s J is out of range: it must be finite and >= 0",
		          function, fmu_number_text(dissipated).text);
		return false;
	}
	const double work = get_d(b, D_INPUT_WORK);
	if (!isfinite(work)) {
		log_error(inst, "%s: the state's input work %s J is out of range: it must be finite", function,
		          fmu_number_text(work).text);
		return false;
	}
	// The parameters that set the structure keep their packaged values, in a state as in a set
	// (check_real): another value could keep the counts and still rearrange the particles.
	for (int32_t i = 0; i < inst->table.count; ++i) {
		const fmu_variable* v = &inst->table.variables[i];
		if (v->source != FMU_SRC_MODEL_PARAMETER || v->variability != FMU_CONSTANT)
			continue;
		const double packaged = sm_document_parameter_value(inst->doc, v->index);
		const double held = value_at(b, 2 * n3 + m + (size_t)v->index);
		if (held != packaged) {
			log_error(
			    inst,
			    "%s: the state gives %s = %s, but %s sets the model's structure (%s in this FMU): " PACKAGED_STRUCTURE
			    "%s=%s)",
			    function, v->name, fmu_number_text(held).text, v->name, fmu_number_text(packaged).text,
			    v->name, fmu_number_text(held).text);
			return false;
		}
	}
	return true;
}

// Every port's inputs are to be given to the simulation when it is next needed; the forces are
// out of date.
static void mark_inputs_dirty(instance* inst)
{
	for (int32_t p = 0; p < inst->port_count; ++p)
		inst->port_dirty[p] = true;
	fmu_forget_derived_values(inst);
}

// Makes a checked state the instance's. All or nothing: a state the model refuses (a parameter
// out of its range, a simulation that cannot start from it) leaves the instance as it was.
static fmi2Status restore_state(instance* inst, const char* function, const unsigned char* b)
{
	int32_t n = inst->particle_count, m = inst->spring_count, np = sm_document_parameter_count(inst->doc);
	const double* d = (const double*)(const void*)(b + HEADER_BYTES);
	double* old = inst->parameter_old;
	port_values* held = malloc(((size_t)inst->port_count + 1) * sizeof *held);
	bool* pending = malloc((size_t)inst->port_count + 1);
	if (!held || !pending) {
		free(held);
		free(pending);
		log_error(inst, "%s: out of memory", function);
		return fmi2Error;
	}
	memcpy(held, d + 6 * n + m + np, (size_t)inst->port_count * sizeof *held);
	for (int32_t p = 0; p < inst->port_count; ++p)
		pending[p] = d[6 * n + m + np + PORT_DOUBLES * (size_t)inst->port_count + p] != 0.0;
	sm_simulation_def solver = inst->solver;
	solver.method = (sm_method)get_i(b, I_METHOD);
	solver.solver = (sm_linear_solver)get_i(b, I_LINEAR_SOLVER);
	solver.jacobian = (sm_jacobian_variant)get_i(b, I_JACOBIAN);
	solver.max_steps = (int32_t)get_i(b, I_MAX_STEPS);
	solver.threads = (int32_t)get_i(b, I_THREADS);
	solver.restart_on_input_change = get_i(b, I_RESTART_ON_INPUT_CHANGE) != 0;
	solver.stability_limit_detection = get_i(b, I_STABILITY_LIMIT_DETECTION) != 0;
	solver.relative_tolerance = get_d(b, D_RTOL);
	solver.absolute_tolerance_position = get_d(b, D_ATOL_POSITION);
	solver.absolute_tolerance_velocity = get_d(b, D_ATOL_VELOCITY);
	solver.max_step = get_d(b, D_MAX_STEP);
	// The parameters first: a state whose parameters give another structure (only a state
	// written by something else than this FMU can hold such values) is refused like a set.
	fmi2Status status = fmu_set_parameters(inst, function, d + 6 * n + m, old) ? fmi2OK : fmi2Error;
	sm_model* model = NULL;
	if (status == fmi2OK && fmu_build_model(inst, function, old, &model) != SM_OK) {
		fmu_put_back_parameters(inst, function, old);
		status = fmi2Error;
	}
	if (status == fmi2OK && get_i(b, I_HAS_SIM)) {
		for (int32_t k = 0; k < m; ++k) {
			if (d[6 * n + k] == 0.0)
				sm_model_set_spring_enabled(model, k, false);
		}
		status = fmu_create_simulation(inst, function, model, &solver, held, pending,
		                               get_d(b, D_TIME) - get_d(b, D_START), d, d + 3 * n);
		if (status != fmi2OK) {
			fmu_put_back_parameters(inst, function, old);
		} else {
			inst->dissipated_offset = get_d(b, D_DISSIPATED) - sm_simulation_dissipated_energy(inst->sim);
			inst->work_offset = get_d(b, D_INPUT_WORK);
		}
	} else if (status == fmi2OK) {
		sm_simulation_destroy(inst->sim);
		inst->sim = NULL;
		inst->sim_dirty = true;
		inst->solver = solver;
		memcpy(inst->held, held, (size_t)inst->port_count * sizeof *held);
		mark_inputs_dirty(inst);
	}
	sm_model_destroy(model);
	free(held);
	free(pending);
	if (status != fmi2OK)
		return status;
	inst->rtol_set = get_i(b, I_RTOL_SET) != 0;
	inst->start_time = get_d(b, D_START);
	inst->time = get_d(b, D_TIME);
	inst->last_successful_time = get_d(b, D_LAST_SUCCESSFUL);
	inst->state = (int)get_i(b, I_STATE);
	return fmi2OK;
}

// In the error state too, as FMI 2.0's table of allowed calls has it, with values "usable for
// debugging only": the state saved there records the error state, and fmi2SetFMUstate refuses it
// (a state to restart from is one saved before, in a non-erroneous state: 2.1.3).
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2GetFMUstate", ST_ANY))
		return fmi2Error;
	if (!FMUstate) {
		log_error(inst, "fmi2GetFMUstate: NULL FMUstate");
		return fmi2Error;
	}
	if (inst->state == ST_INITIALIZATION && fmu_ensure_simulation(inst, "fmi2GetFMUstate") != fmi2OK)
		return fmi2Error;
	saved_state* s = save_state(inst, *FMUstate);
	if (!s) {
		log_error(inst, "fmi2GetFMUstate: out of memory");
		return fmi2Error;
	}
	if (*FMUstate && s != *FMUstate) {
		saved_state* old = *FMUstate;
		free(old->bytes);
		free(old);
	}
	*FMUstate = s;
	return fmi2OK;
}

// Allowed in the error state too: FMI 2.0 (2.1.3) names restoring a state saved before as the
// way to continue after fmi2Error. If the state cannot be restored, the instance stays in the
// error state.
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SetFMUstate", ST_ANY))
		return fmi2Error;
	if (!FMUstate) {
		log_error(inst, "fmi2SetFMUstate: NULL FMUstate");
		return fmi2Error;
	}
	saved_state* s = FMUstate;
	write_checksum(s);
	if (!valid_state(inst, "fmi2SetFMUstate", s->bytes, s->size))
		return fmi2Error;
	if (get_i(s->bytes, I_STATE) == ST_ERROR) {
		log_error(
		    inst,
		    "fmi2SetFMUstate: the state was saved in the error state, for debugging only: restore a state "
		    "saved before the error");
		return fmi2Error;
	}
	return restore_state(inst, "fmi2SetFMUstate", s->bytes);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2FreeFMUstate", ST_ANY))
		return fmi2Error;
	if (!FMUstate)
		return fmi2OK;
	saved_state* s = *FMUstate;
	if (s) {
		free(s->bytes);
		free(s);
	}
	*FMUstate = NULL;
	return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SerializedFMUstateSize", ST_ANY))
		return fmi2Error;
	if (!FMUstate || !size) {
		log_error(inst, "fmi2SerializedFMUstateSize: NULL argument");
		return fmi2Error;
	}
	*size = ((const saved_state*)FMUstate)->size;
	return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2SerializeFMUstate", ST_ANY))
		return fmi2Error;
	if (!FMUstate || !serializedState) {
		log_error(inst, "fmi2SerializeFMUstate: NULL argument");
		return fmi2Error;
	}
	saved_state* s = FMUstate;
	if (size < s->size) {
		log_error(inst, "fmi2SerializeFMUstate: buffer of %zu bytes, the state needs %zu", size, s->size);
		return fmi2Error;
	}
	write_checksum(s);
	memcpy(serializedState, s->bytes, s->size);
	return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* FMUstate)
{
	instance* inst = c;
	if (!fmu_allowed(inst, "fmi2DeSerializeFMUstate", ST_ANY))
		return fmi2Error;
	if (!serializedState || !FMUstate) {
		log_error(inst, "fmi2DeSerializeFMUstate: NULL argument");
		return fmi2Error;
	}
	if (!valid_state(inst, "fmi2DeSerializeFMUstate", (const unsigned char*)serializedState, size))
		return fmi2Error;
	saved_state* s = malloc(sizeof *s);
	unsigned char* bytes = malloc(size);
	if (!s || !bytes) {
		free(s);
		free(bytes);
		log_error(inst, "fmi2DeSerializeFMUstate: out of memory");
		return fmi2Error;
	}
	memcpy(bytes, serializedState, size);
	s->size = size;
	s->bytes = bytes;
	s->checksummed = true;
	if (*FMUstate) {
		saved_state* old = *FMUstate;
		free(old->bytes);
		free(old);
	}
	*FMUstate = s;
	return fmi2OK;
}

// springmass FMU: what the files of the FMU binary share. The instance and the states of the FMI
// 2.0 state machine, logging, the model and simulation helpers (defined in fmu_cosim.c) and the
// value helpers (fmu_values.c) that the entry points (fmu_cosim.c, fmu_values.c,
// fmu_derivatives.c, fmu_step.c) and the FMU state (fmu_state.c) call. Internal: the binary
// exports the fmi2* entry points only, nothing declared here.
#pragma once

#include "fmu_model.h"

#include "fmi2Functions.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// ---------------------------------------------------------------------------------------------
// Instance
// ---------------------------------------------------------------------------------------------

// States of the FMI 2.0 Co-Simulation state machine, as bits so that each function states the
// set in which it is allowed.
enum {
	ST_INSTANTIATED = 1 << 0,
	ST_INITIALIZATION = 1 << 1,
	ST_STEP_COMPLETE = 1 << 2,
	ST_STEP_FAILED = 1 << 3,
	ST_TERMINATED = 1 << 4,
	ST_ERROR = 1 << 5,
};
#define ST_ANY                                                                                               \
	(ST_INSTANTIATED | ST_INITIALIZATION | ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED | ST_ERROR)
#define ST_RUNNING (ST_INITIALIZATION | ST_STEP_COMPLETE | ST_STEP_FAILED | ST_TERMINATED | ST_ERROR)

// Log categories, as bits.
enum {
	LOG_EVENTS = 1 << 0,
	LOG_WARNING = 1 << 1,
	LOG_DISCARD = 1 << 2,
	LOG_ERROR = 1 << 3,
	LOG_SOLVER = 1 << 4,
};

// Held values of a port: prescribed or read position [m], velocity [m/s], force [N], and the
// derivatives fmi2SetRealInputDerivatives gives (a motion port's acceleration [m/s^2] from its
// velocity's, a force port's rate [N/s]), with the simulation's time at which they were last given
// to it [s]. Doubles only: an FMU state holds PORT_DOUBLES per port.
typedef struct port_values {
	double position[3];
	double velocity[3];
	double force[3];
	double acceleration[3];
	double force_rate[3];
	double since;
} port_values;
#define PORT_DOUBLES (sizeof(port_values) / sizeof(double))

// An FMU instance: what an fmi2Component points to.
typedef struct instance {
	char* name;
	fmi2CallbackLogger logger;
	fmi2ComponentEnvironment environment;
	unsigned log_mask;
	int state;

	char* text;  // resources/model.json as read
	size_t length;
	char* parameters;  // resources/parameters.txt as read, NULL when the FMU has none
	size_t parameters_length;
	sm_document* doc;
	fmu_table table;
	int32_t particle_count;
	int32_t spring_count;
	int32_t port_count;
	sm_port* ports;   // particle indices of the ports (names stay in doc)
	int32_t* driven;  // the particles of the motion ports, driven_count of them
	int32_t driven_count;

	// Settings and inputs.
	sm_simulation_def solver;
	bool rtol_set;  // solver.rtol set explicitly: the experiment's tolerance does not override it
	double start_time;
	bool stop_time_defined;
	double stop_time;
	port_values* held;  // per port: the inputs as set, the start values until then
	bool* port_dirty;   // inputs set since they were last given to the simulation

	// The running simulation (created when first needed in initialisation mode).
	sm_simulation* sim;
	bool sim_dirty;  // fixed parameters or settings changed: create it again
	double time;     // the FMU's time: start_time + the simulation's time [s]
	double last_successful_time;
	double dissipated_offset;  // added to the simulation's dissipated energy after a restore [J]
	double work_origin;        // the simulation's input work that counts as none (fmu_input_work) [J]
	double work_offset;        // added to the simulation's input work past work_origin (fmu_input_work) [J]
	int32_t breaks_logged;
	double* forces;  // 3 per particle, valid while forces_valid
	bool forces_valid;
	sm_energies energies;  // kinetic, elastic and gravitational, valid while energies_valid [J]
	bool energies_valid;
	double* scratch;        // 5 * 3 per particle for directional and output derivatives
	double* parameter_old;  // the model-file parameters' values before a change that may fail
	double* parameter_new;  // the values such a change sets, one per parameter
} instance;

// ---------------------------------------------------------------------------------------------
// Logging
// ---------------------------------------------------------------------------------------------

// Whether the importer takes messages of a category (LOG_* bits) now.
bool fmu_logging(const instance* inst, unsigned category);

// Formats a message and hands it to the importer's logger if its category is on.
void fmu_logf(instance* inst, fmi2Status status, unsigned category, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

// Logs an error (category logStatusError); the arguments are those of printf.
#define log_error(inst, ...) fmu_logf((inst), fmi2Error, LOG_ERROR, __VA_ARGS__)

// The text of a number for a message (fmu_number_text).
typedef struct number_text_t {
	char text[SM_NUMBER_TEXT_CAPACITY];
} number_text_t;

// A number in the fewest digits that read back to it, valid until the end of the full expression.
number_text_t fmu_number_text(double x);

// Checks the state machine: logs and returns false if `function` is not allowed in `states` now.
bool fmu_allowed(instance* inst, const char* function, int states);

// ---------------------------------------------------------------------------------------------
// Model and simulation
// ---------------------------------------------------------------------------------------------

// How to get an FMU of another structure, for the messages that refuse one.
#define PACKAGED_STRUCTURE                                                                                   \
	"this FMU's variables were made for the structure at packaging: package the model with that value "      \
	"(springmass fmu MODEL -o NAME.fmu --set "

// Builds the model with the current parameter values, refusing one of another structure than packaged.
sm_status fmu_build_model(instance* inst, const char* function, const double* before, sm_model** out);

// Makes a simulation of the model, state (or initial state) and inputs the instance's, all or nothing;
// a message names `function`, the entry point.
fmi2Status fmu_create_simulation(instance* inst, const char* function, sm_model* model,
                                 const sm_simulation_def* solver, const port_values* held,
                                 const bool* pending, double sim_time, const double* x, const double* v);

// Makes sure a simulation with the current settings exists and has taken the inputs set.
fmi2Status fmu_ensure_simulation(instance* inst, const char* function);

// Gives the inputs set since the last step to the simulation, at the current communication point.
fmi2Status fmu_apply_inputs(instance* inst, const char* function);

// The state, the inputs or the model changed: the forces and energies kept for it are out of date.
void fmu_forget_derived_values(instance* inst);

// The force on every particle at the current state [N] (3 per particle), evaluated once per state.
const double* fmu_current_forces(instance* inst);

// The energy dissipated since the start [J], never negative (energy.dissipated and a saved
// state's; the reason is in fmu_cosim.c). Needs the simulation.
double fmu_dissipated_energy(const instance* inst);
// The work the inputs did since the start (energy.input) [J].
double fmu_input_work(const instance* inst);

// Sets the model-file parameters to values[] all at once, old ones in old[]; false if the model refuses.
bool fmu_set_parameters(instance* inst, const char* function, const double* values, double* old);

// Puts back the parameter values old[] of fmu_set_parameters (the error state if that fails).
void fmu_put_back_parameters(instance* inst, const char* function, const double* old);

// ---------------------------------------------------------------------------------------------
// Values (fmu_values.c)
// ---------------------------------------------------------------------------------------------

// The variable of a value reference if it exists and has the type asked for; NULL, logged, if not.
const fmu_variable* fmu_lookup(instance* inst, const char* function, fmi2ValueReference vr, fmu_type type);

// False, logged, for a NULL array with nvr > 0.
bool fmu_check_arrays(instance* inst, const char* function, const void* vr, size_t nvr, const void* value);

// The kinetic, elastic and gravitational energies at the current state, evaluated once per state.
const sm_energies* fmu_current_energies(instance* inst);

// The value of a Real variable now (in SI units).
double fmu_real_value(instance* inst, const fmu_variable* v);

// fmi2OK, or fmi2Warning, logged, when a value read (`what`: "" or "the derivative of ") of
// `overflowing` is beyond the range of a double.
fmi2Status fmu_overflow_warning(instance* inst, const char* function, const char* what,
                                const fmu_variable* overflowing);

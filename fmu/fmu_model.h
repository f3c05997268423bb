// springmass FMU: the variable table of a model file, its GUID and its modelDescription.xml, and
// the parameter values an FMU carries beside the file (resources/parameters.txt).
//
// One table is the single source of truth for the FMU's interface: the packager writes
// modelDescription.xml from it and the runtime (fmu_values.c) resolves value references with
// it. Value references are the indices into the table, so both sides agree by construction.
// This layer knows only the public model-file API (sm_document), never a force law.
#pragma once

#include "springmass/model_file.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// FMI base type of a variable.
typedef enum fmu_type {
	FMU_REAL = 0,
	FMU_INTEGER,
	FMU_BOOLEAN,
	FMU_STRING,
} fmu_type;

/// FMI causality.
typedef enum fmu_causality {
	FMU_PARAMETER = 0,
	FMU_INPUT,
	FMU_OUTPUT,
	FMU_LOCAL,
} fmu_causality;

/// FMI variability.
typedef enum fmu_variability {
	FMU_CONSTANT = 0,  ///< a model-file parameter that sets the structure (fmu_table_create)
	FMU_FIXED,
	FMU_TUNABLE,
	FMU_CONTINUOUS,
} fmu_variability;

/// What a variable reads or writes in the runtime.
typedef enum fmu_source {
	FMU_SRC_MODEL_PARAMETER = 0,   ///< index = parameter index of the document
	FMU_SRC_SOLVER_RTOL,           ///< relative tolerance [1]
	FMU_SRC_SOLVER_ATOL_POSITION,  ///< absolute tolerance of positions [m]
	FMU_SRC_SOLVER_ATOL_VELOCITY,  ///< absolute tolerance of velocities [m/s]
	FMU_SRC_SOLVER_MAX_STEP,       ///< largest internal step [s], 0 = unlimited
	FMU_SRC_SOLVER_MAX_STEPS,      ///< internal steps allowed per communication step
	FMU_SRC_SOLVER_THREADS,        ///< threads of the pcg solver's loops
	FMU_SRC_SOLVER_METHOD,         ///< "bdf" or "adams"
	FMU_SRC_SOLVER_LINEAR_SOLVER,  ///< "auto", "dense", "klu", "pcg", "cholmod"
	FMU_SRC_SOLVER_JACOBIAN,       ///< "exact" or "definite"
	FMU_SRC_SOLVER_INPUT_CHANGES,  ///< "restart" or "keep": what an input that changes does
	FMU_SRC_SOLVER_STABILITY,      ///< BDF's stability limit detection: on or off
	FMU_SRC_PORT_POSITION,         ///< index = port, component 0..2 [m]
	FMU_SRC_PORT_VELOCITY,         ///< index = port, component 0..2 [m/s]
	FMU_SRC_PORT_FORCE,            ///< index = port, component 0..2 [N]
	FMU_SRC_PARTICLE_POSITION,     ///< index = particle, component 0..2 [m]
	FMU_SRC_PARTICLE_VELOCITY,     ///< index = particle, component 0..2 [m/s]
	FMU_SRC_ENERGY_KINETIC,        ///< [J]
	FMU_SRC_ENERGY_ELASTIC,        ///< [J]
	FMU_SRC_ENERGY_GRAVITY,        ///< [J]
	FMU_SRC_ENERGY_DISSIPATED,     ///< [J]
	FMU_SRC_ENERGY_INPUT,          ///< the inputs' work [J]
} fmu_source;

/// One scalar variable. Its value reference is its index in the table.
typedef struct fmu_variable {
	char* name;         ///< structured name ("tip.fx", "p[3].vz", "solver.rtol")
	char* description;  ///< one line
	fmu_type type;
	fmu_causality causality;
	fmu_variability variability;
	const char* unit;  ///< static unit name ("m", "N", ...) or NULL
	fmu_source source;
	int32_t index;      ///< parameter, port or particle index (see fmu_source)
	int32_t component;  ///< 0..2 for vector quantities
	bool has_start;     ///< parameters and inputs have a start value
	double start_real;
	int32_t start_integer;
	bool start_boolean;
	const char* start_string;  ///< static string
} fmu_variable;

/// The interface of one model file.
/// A motion port a spring joins to another's particle, with the sm_force_term flags of the springs
/// joining them: its position enters the other's force if any is set, its velocity if
/// SM_FORCE_DAMPING is.
typedef struct fmu_neighbour {
	int32_t port;
	uint8_t terms;
} fmu_neighbour;

typedef struct fmu_table {
	fmu_variable* variables;
	int32_t count;
	char guid[40];           ///< "{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}" (fmu_package_guid)
	char* model_identifier;  ///< C identifier from the model's name
	char* model_name;
	char* description;
	double stop_time;  ///< default experiment [s]
	double step_size;  ///< default communication step [s]
	double tolerance;  ///< default relative tolerance [1]
	/// The motion ports whose particles a spring of some force joins to each port's particle, the
	/// ports whose inputs its force outputs depend on besides its own: port p's are
	/// port_neighbours[port_neighbour_start[p]] up to port_neighbours[port_neighbour_start[p + 1]],
	/// ascending, none for a force or probe port.
	int32_t port_count;
	int32_t* port_neighbour_start;  ///< port_count + 1 offsets into port_neighbours
	fmu_neighbour* port_neighbours;
	/// Per port, the sm_force_term flags of the springs at its particle (its force's dependencies
	/// on its own position and velocity), and whether mass damping can act (on its own velocity).
	uint8_t* port_force_terms;
	bool mass_damping;
	/// Per port, the sm_potential_term flags of its particle: which components of a motion port's
	/// position the gravitational energy depends on, and whether the elastic energy does.
	uint8_t* port_potential_terms;
} fmu_table;

/// Builds the table of a parsed model file. `text`/`length` are the file's bytes and `parameters`
/// those of resources/parameters.txt, used only for the GUID: the caller parses doc from them (the
/// table is doc's).
///
/// A model-file parameter is tunable (changeable between communication steps) when it feeds
/// only constants (stiffness, damping, masses, rest lengths, break strains, gravity, mass
/// damping, loads), which a running simulation can take over. It is fixed (settable only before
/// initialisation) when it also feeds the initial state (positions, velocities), which
/// particles are held, a setting or a spring's kind. It is a constant (causality local,
/// variability constant: not settable at all) when it feeds the particle or spring counts,
/// which particles springs join, and with them the particle each port is at: the FMU's
/// variables (p[i].x, the ports) are made for one structure at packaging.
/// This is decided from the places the model file names the parameter
/// (sm_document_parameter_uses), whatever its value. Returns SM_OK, or an error with the message
/// in err (e.g. two variables with the same name); on error *table is zeroed and nothing is
/// leaked.
/// For an FMU whose resources/parameters.txt holds `parameters` (NULL for none), doc is the model
/// file with those values applied (fmu_document_parse): the parameters' start values and
/// constants, the counts, the ports and the default experiment are the model's with them, and the
/// GUID is fmu_package_guid of both texts.
sm_status fmu_table_create(const sm_document* doc, const char* text, size_t length, const char* parameters,
                           size_t parameters_length, fmu_table* table, sm_error* err);

/// Frees what the table owns; accepts a zeroed table.
void fmu_table_destroy(fmu_table* table);

/// The GUID of an FMU's resources: a 128-bit FNV-1a hash, written as
/// "{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}" (39 characters and NUL), of "springmass
/// MAJOR.MINOR.PATCH" (the SM_VERSION_* of base.h) and a NUL byte, continued over the model file's
/// bytes, and when `parameters` is not NULL (the FMU has resources/parameters.txt) over a NUL byte
/// and the parameters' bytes. A model file holds no NUL byte (the loader refuses one), so the parts
/// cannot be shifted into each other: another version, model file or parameter values give another
/// GUID.
void fmu_package_guid(const char* text, size_t length, const char* parameters, size_t parameters_length,
                      char guid[40]);

/// The resource, beside model.json, that holds the parameter values given at packaging
/// (`springmass fmu MODEL --set NAME=VALUE`); an FMU packaged without any has none.
#define FMU_PARAMETERS_RESOURCE "parameters.txt"

/// The text of resources/parameters.txt for `set`, a document parsed from the model file `text`
/// whose parameters were then set: one line "NAME=VALUE\n" for each parameter whose value differs
/// from the file's (as sm_document_set_parameter compares them: 0 is the file's -0, which a line
/// "NAME=0" would leave as it is), the value in the shortest of 15, 16 or 17 significant digits
/// that reads back to the same double.
/// The lines are in the file's order of parameters, except that a value the model refuses before
/// others are set (a rope's end moved onto its start before the start moves away) comes after
/// them; if no such order is found, they are in `order` (order_count distinct parameter indices,
/// an order the caller set them in): applied one at a time in the order written, every value is
/// accepted. With `order` NULL, values that no such order takes (a rope's start and end swapped)
/// are written in the file's order, unchecked: fmu_apply_parameters takes them together, as `set`
/// has them. Messages name `source_name` (the model file). Returns a malloc'ed NUL-terminated text
/// and its length (0 when no value differs), or NULL with err set: out of memory, or values the
/// model refuses in every such order (naming the parameter).
/// Whether a parameter's value set is the one it has: the same double, down to the sign of a zero
/// (a parameter of 0 set to -0 starts a velocity at -0, as the file giving -0.0 does:
/// sm_document_set_parameter).
bool fmu_same_parameter_value(double a, double b);

char* fmu_parameters_text(const sm_document* set, const char* text, size_t length, const char* source_name,
                          const int32_t* order, int32_t order_count, size_t* parameters_length,
                          sm_error* err);

/// Applies the text of resources/parameters.txt to a document parsed from the model file: one
/// "NAME=VALUE" a line (the last line's line feed may be missing), each a parameter of the model
/// named once with a finite number (read in the C locale whatever the importer's), set in the order
/// of the lines; from a value the model refuses after the lines before on, the rest are set with
/// all the others at the end, together (values valid only together, which no order takes one at a
/// time). Refuses an empty text, a malformed line, an unknown or repeated parameter and values the
/// model refuses, with a message "SOURCE:LINE: ..." naming the line (source_name, e.g.
/// "resources/parameters.txt"; for values refused together too, the first line refused); the
/// document may then hold the values of the lines before.
sm_status fmu_apply_parameters(sm_document* doc, const char* parameters, size_t parameters_length,
                               const char* source_name, sm_error* err);

/// The document an FMU simulates: the model file `text` parsed (messages name `source_name`) with
/// the values of resources/parameters.txt applied when `parameters` is not NULL (messages name
/// "resources/parameters.txt"). NULL with err set on failure; the caller destroys the result.
sm_document* fmu_document_parse(const char* text, size_t length, const char* source_name,
                                const char* parameters, size_t parameters_length, sm_error* err);

/// modelDescription.xml of the table, as a malloc'ed NUL-terminated string (NULL on OOM).
/// `generation_date` is an ISO 8601 UTC time stamp or NULL to leave it out.
char* fmu_model_description(const fmu_table* table, const char* generation_date);

/// documentation/index.html of the table (fmu_documentation.c): the model, how the FMU steps,
/// its inputs, outputs, parameters and constants with their value references, units and start
/// values, and, when `licenses` says the FMU has documentation/licenses/, where its licences are;
/// a malloc'ed NUL-terminated string (NULL on OOM).
char* fmu_documentation_html(const fmu_table* table, bool licenses);

/// The FMI names of a causality ("parameter", "input", "output", "local") and of a variability
/// ("constant", "fixed", "tunable", "continuous").
const char* fmu_causality_name(fmu_causality causality);
const char* fmu_variability_name(fmu_variability variability);

/// Writes a C identifier made from `name` (letters, digits and '_'; a leading digit, an empty name
/// or a C keyword such as "int" gets a "model_" prefix) into a malloc'ed string.
char* fmu_identifier(const char* name);

#ifdef __cplusplus
}
#endif

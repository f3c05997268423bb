// springmass: model files (JSON, format documented in docs/model-format.md).
//
// A document is a parsed model file: named parameters, particles, springs, structures, ports
// and default settings. Building it gives an sm_model with the parameters' current values;
// changing a parameter and building again gives a model of the same topology with new
// constants (this is how the FMU's tunable parameters work).
#pragma once

#include "springmass/model.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Current version of the format (the "springmass" key of a file).
#define SM_FORMAT_VERSION 1

/// How a port meets the outside world.
typedef enum sm_port_kind {
	SM_PORT_FORCE = 0,  ///< the outside applies a force [N]; reads position [m] and velocity [m/s]
	/// the outside prescribes position [m] and velocity [m/s]; reads the force the model (springs,
	/// damping, gravity, loads) exerts on the particle [N], not its reaction, which is minus that
	/// (model.h)
	SM_PORT_MOTION,
	SM_PORT_PROBE,  ///< read only: position [m] and velocity [m/s]
} sm_port_kind;

/// A named particle through which the model meets the outside world.
typedef struct sm_port {
	const char* name;  ///< owned by the document
	int32_t particle;  ///< particle index in the built model
	sm_port_kind kind;
} sm_port;

/// Settings a file may carry for simulations and FMUs ("simulation" and "fmu" objects).
typedef struct sm_document_settings {
	double stop_time;          ///< default end of a run [s]; default 1
	double output_interval;    ///< default output interval [s]; default 0.01
	sm_simulation_def solver;  ///< integrator options
	bool particle_variables;   ///< FMU exposes every particle's position and velocity; default true
} sm_document_settings;

typedef struct sm_document sm_document;

/// Loads and validates a model file. On error returns NULL and fills err: a syntax error names
/// the file, line and column (`model.json:3:14: ...`); a rule broken names the path in the
/// document, the value and the rule (`model.json: springs[3].b: no particle named "bobb"`).
/// Messages show the file's path, and an OBJ file's, with control characters escaped and, past
/// 140 bytes, by its end (`...` and its last characters), so that they end with what is wrong.
/// Only regular files are read (a directory, a device or a FIFO is refused at once); files larger
/// than 1 GiB, and models of more than 2^22 particles or springs, are refused. Loading takes time
/// in proportion to the file's size.
SM_API sm_document* sm_document_load(const char* path, sm_error* err);

/// Same from text in memory; `source_name` is used in messages in place of a file name. The OBJ
/// file of a mesh's "file" is found relative to the current directory, unless its path is absolute
/// (sm_document_load finds it relative to the model file's folder).
SM_API sm_document* sm_document_parse(const char* text, size_t length, const char* source_name,
                                      sm_error* err);
/// sm_document_parse with the OBJ files of meshes found relative to `folder` (NULL or "": the
/// current directory), as sm_document_load does for a model file in that folder.
SM_API sm_document* sm_document_parse_in_folder(const char* text, size_t length, const char* source_name,
                                                const char* folder, sm_error* err);

/// Frees a document; accepts NULL.
SM_API void sm_document_destroy(sm_document* doc);

/// Model name ("name"), a C identifier-safe string, and one-line description ("" if none).
SM_API const char* sm_document_name(const sm_document* doc);
SM_API const char* sm_document_description(const sm_document* doc);

/// Room for sm_text_for_terminal's output for a text of `length` bytes, the NUL included [bytes].
#define SM_TERMINAL_TEXT_CAPACITY(length) (6 * (size_t)(length) + 1)

/// A name or description of a model file as a terminal can show it, the way the library's
/// messages show them: control characters (the tab too), line breaks and the zero-width and
/// bidirectional formatting characters, which a terminal would act on or not show, as \uXXXX; a
/// byte that begins no well-formed UTF-8 character as \xNN; every other character as it is.
/// `out` has room for SM_TERMINAL_TEXT_CAPACITY(strlen(text)) bytes. A NULL text (the name or
/// description of a NULL document) gives the empty text; a NULL out, nothing.
SM_API void sm_text_for_terminal(char* out, const char* text);

/// Builds the model with the parameters' current values. The caller owns the result.
SM_API sm_status sm_document_build(const sm_document* doc, sm_model** model, sm_error* err);

/// Named parameters, in file order.
SM_API int32_t sm_document_parameter_count(const sm_document* doc);
SM_API const char* sm_document_parameter_name(const sm_document* doc, int32_t index);
SM_API double sm_document_parameter_value(const sm_document* doc, int32_t index);  // NaN out of range
/// Index of a parameter by name, or -1.
SM_API int32_t sm_document_parameter_index(const sm_document* doc, const char* name);
/// What a parameter's value feeds, as flags or-ed over every place the file uses it (0 for a
/// parameter the file never uses). A program that lets users change parameters while a model
/// runs (the FMU does) changes in place only those that feed SM_PARAMETER_CONSTANTS alone.
typedef enum sm_parameter_use {
	/// masses, densities, stiffness, damping, rest lengths, break strains, sections, gravity,
	/// mass damping, loads
	SM_PARAMETER_CONSTANTS = 1 << 0,
	/// initial positions and velocities, among them a structure's geometry (which sets its
	/// springs' rest lengths too) and a mesh's vertices
	SM_PARAMETER_INITIAL_STATE = 1 << 1,
	/// which particles are held: the corners of a box in "fixed"
	SM_PARAMETER_MOTION = 1 << 2,
	/// how many particles and springs there are and which particles springs join: a structure's
	/// segment or grid counts, a mesh's triangles; every particle index after them moves too, and
	/// with them the particles ports and "fixed" name
	SM_PARAMETER_COUNTS = 1 << 3,
	/// the "simulation" settings (stop time, tolerances, steps)
	SM_PARAMETER_SETTINGS = 1 << 4,
	/// which law a spring follows: the rest length of a spring without a "kind" (0 makes it
	/// zero-length, any other value rest-length)
	SM_PARAMETER_SPRING_KINDS = 1 << 5,
	/// which particle a structure reference names: an index of "cloth[n - 1, n / 2]" (ports,
	/// "fixed", a spring's ends)
	SM_PARAMETER_PARTICLE_REFERENCES = 1 << 6,
} sm_parameter_use;

/// The uses (sm_parameter_use flags) of a parameter; 0 for an unused one or an index out of
/// range. They depend on where the file names the parameter, not on its value.
SM_API uint32_t sm_document_parameter_uses(const sm_document* doc, int32_t index);

/// The SI unit of the values a parameter stands for, when all have the same one: "kg" for a mass,
/// "N/m" for a stiffness, "1" for a strain or a relative tolerance, and so on, as
/// docs/model-format.md gives each key's ("N.s/m" for N s/m, "m/s2" for m/s^2). "" for a parameter
/// that stands for values of different units, for a count or an index, for a value whose unit its
/// key alone does not tell (`atol`, which sets the tolerances of positions [m] and velocities
/// [m/s]; a single spring's `section`, a width [m] or an area [m^2], and its per-section
/// constants), or for nothing, unless the file's "parameter_units" gives it one: then that one
/// (the loader checked that every value whose key tells a unit has it). NULL for an index out of
/// range. Like the uses, it depends on where the file names the parameter, not on its value.
SM_API const char* sm_document_parameter_unit(const sm_document* doc, int32_t index);
/// Sets a parameter's value; fails (document unchanged) if the model built with it would be
/// invalid, with the message naming the element that breaks a rule. A parameter may feed any
/// number of the file, counts included; a value that changes the number of particles fails if
/// an initial state is set with sm_document_set_initial_state.
SM_API sm_status sm_document_set_parameter(sm_document* doc, int32_t index, double value, sm_error* err);
/// Sets every parameter at once, values[i] for parameter i (sm_document_parameter_count values,
/// in file order), checked together: values that are valid only together (a rope's new start
/// beyond its old end, with the new end) are taken whatever their order, where one
/// sm_document_set_parameter after the other could be refused. All or nothing, as above; the
/// message names the parameters that changed.
SM_API sm_status sm_document_set_parameters(sm_document* doc, const double* values, sm_error* err);

/// Ports, in file order. A port's name stays valid as long as the document. An index out of range
/// (or a NULL document) gives a port with a NULL name and particle -1 (kind SM_PORT_PROBE).
SM_API int32_t sm_document_port_count(const sm_document* doc);
SM_API sm_port sm_document_port(const sm_document* doc, int32_t index);
/// Index of a port by name, or -1.
SM_API int32_t sm_document_port_index(const sm_document* doc, const char* name);

/// A structure of the file (its "structures" array) as its builder made it.
typedef struct sm_structure_info {
	const char* name;    ///< owned by the document
	const char* type;    ///< "rope", "sheet", "block" or "mesh"
	sm_structure range;  ///< its particles, springs, grid shape and springs per group (structures.h)
} sm_structure_info;

/// Structures, in file order; an index out of range gives a NULL name. The ranges are valid until
/// the next sm_document_set_parameter (a parameter may change counts) or destroy.
SM_API int32_t sm_document_structure_count(const sm_document* doc);
SM_API sm_structure_info sm_document_structure(const sm_document* doc, int32_t index);
/// The OBJ file a mesh structure read its vertices and triangles from, as the file's "file" gives
/// it (owned by the document); NULL for a structure that reads none or an index out of range. The
/// file was read when the document was loaded: the document needs it no more.
SM_API const char* sm_document_structure_file(const sm_document* doc, int32_t index);
/// The path that OBJ file was read from: a relative "file" joined to the folder of the model file
/// (sm_document_load) or to the folder given (sm_document_parse_in_folder), as it is otherwise; a
/// relative result is the current directory's at loading. Owned by the document; NULL as above.
SM_API const char* sm_document_structure_file_path(const sm_document* doc, int32_t index);

/// Number of particles and of springs of the model sm_document_build gives with the parameters'
/// current values, without building it (0 for NULL): 3 times the particle count is the length of
/// sm_document_set_initial_state's arrays, and particles are numbered 0 to count - 1 for
/// sm_document_particle_name. A parameter that feeds SM_PARAMETER_COUNTS changes them.
SM_API int32_t sm_document_particle_count(const sm_document* doc);
SM_API int32_t sm_document_spring_count(const sm_document* doc);

/// The terms of the potential energy (sm_model_energies) a particle's position enters for some
/// values of the parameters, whatever their current ones: a term whose constants the file gives as
/// numbers 0 is left out.
typedef enum sm_potential_term {
	/// the potential of the constant force on the particle, its weight m g plus its loads [N],
	/// along x, y or z: gravity's or a load's component there is a parameter or a number other than 0
	SM_POTENTIAL_CONSTANT_X = 1 << 0,
	SM_POTENTIAL_CONSTANT_Y = 1 << 1,
	SM_POTENTIAL_CONSTANT_Z = 1 << 2,
	/// the elastic energy: a spring ends at the particle whose stiffness is a parameter or a number
	/// other than 0 (a spring of stiffness 0 is a damper alone)
	SM_POTENTIAL_ELASTIC = 1 << 3,
} sm_potential_term;

/// Fills terms[i] with the sm_potential_term flags of particle i, for the sm_document_particle_count
/// particles. A program that declares what the energies depend on (the FMU's ModelStructure) reads
/// them; they hold until the next sm_document_set_parameter changes the counts.
SM_API void sm_document_potential_terms(const sm_document* doc, uint8_t* terms);

/// The forces (sm_model_forces) a spring can exert for some values of the parameters, whatever
/// their current ones: a constant the file gives as the number 0 exerts none.
typedef enum sm_force_term {
	/// the elastic force ks (L - l0) u [N]: its stiffness is a parameter or a number other than 0
	SM_FORCE_ELASTIC = 1 << 0,
	/// the damping force kd (u . dv) u [N], along the spring: its damping is a parameter or a number
	/// other than 0
	SM_FORCE_DAMPING = 1 << 1,
} sm_force_term;

/// Fills terms[s] with the sm_force_term flags of spring s, for the sm_document_spring_count
/// springs (terms may be NULL), and returns whether mass damping, -alpha m v on every particle
/// [N], can act: alpha is a parameter or a number other than 0. A program that declares what the
/// forces depend on (the FMU's ModelStructure) reads them; they hold until the next
/// sm_document_set_parameter changes the counts. False for NULL.
SM_API bool sm_document_force_terms(const sm_document* doc, uint8_t* terms);

/// Name of a particle ("anchor", or "cloth[3,4]" for structure particles: "name[row,column]"
/// for a sheet, "name[row,column,layer]" for a block, "name[i]" for a rope or a mesh), NULL if
/// unnamed or out of range. Valid until the next sm_document_set_parameter or destroy.
SM_API const char* sm_document_particle_name(const sm_document* doc, int32_t particle);
/// Index of a particle by its name (as sm_document_particle_name gives it), or -1.
SM_API int32_t sm_document_particle_index(const sm_document* doc, const char* name);

/// The file's "simulation" settings, with the defaults for those it leaves out.
SM_API sm_document_settings sm_document_get_settings(const sm_document* doc);

/// Replaces the initial positions [m] and velocities [m/s] of all particles (3 per particle,
/// sm_document_particle_count particles; v may be NULL for zero), e.g. with a static equilibrium,
/// so that building or saving gives a model that starts there. Rest lengths stay those of the
/// file's own positions (a hanging cloth keeps its stretch). The state stays through parameter
/// changes, which may then not change the number of particles. x NULL with v NULL drops a state
/// set before (nothing to do if none is): building and saving start from the file's positions
/// and velocities with the parameters' current values again, and parameters may change the
/// counts again; x NULL with v not NULL is SM_ERROR_INVALID_ARGUMENT. A state that is not finite, or
/// that puts a spring's particles 1.3e154 m or more apart (the square of its length overflows, as the
/// loader refuses in a file), is SM_ERROR_NOT_FINITE, the document unchanged.
SM_API sm_status sm_document_set_initial_state(sm_document* doc, const double* x, const double* v,
                                               sm_error* err);

/// Writes the document in canonical form to a file, or to a malloc'ed string the caller frees
/// (NULL on error). Structures are expanded into explicit particles and springs (keeping their
/// particles' names), rest lengths are written out, and every value that was a parameter
/// reference stays one (values a structure derives from a parameter, such as a particle's share
/// of a total mass, are written as numbers). Loading the result builds the same model, with the
/// same sm_document_parameter_unit for every parameter it keeps that has one: "parameter_units"
/// gives the units of those the text names where a key tells none (a structure's per-section
/// constants, saved as single springs'). The file is written whole or not at all: beside the one
/// it replaces, then renamed over it (keeping its permissions), so that a failed save (a full
/// disk) leaves an earlier file as it was; a link or a device, or a file in a folder that takes no
/// new files, is written where it is.
SM_API sm_status sm_document_save(const sm_document* doc, const char* path, sm_error* err);
SM_API char* sm_document_to_json(const sm_document* doc, sm_error* err);

/// The model file as the document was loaded from it (its parameters, structures and references
/// as written, with the parameters' values of the file), but with the vertices and triangles of
/// every mesh that reads an OBJ file written inline in place of its "file", so that it loads
/// without the OBJ files to the same model, bit for bit: a malloc'ed string the caller frees, NULL
/// on error (out of memory). A file whose meshes read no OBJ file comes out as JSON of the same
/// meaning, laid out anew. This is what an FMU packs (`springmass fmu`).
SM_API char* sm_document_to_self_contained_json(const sm_document* doc, sm_error* err);

#ifdef __cplusplus
}
#endif

// springmass: common definitions (export macro, status codes, error text).
// SI units throughout: metres, kilograms, seconds, newtons.
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#if defined(__GNUC__) || defined(__clang__)
#define SM_API __attribute__((visibility("default")))
#else
#define SM_API
#endif

/// Version of these headers, major.minor.patch (CMakeLists.txt reads it from here). Before 1.0
/// a new minor version may change the API; a new patch version does not.
#define SM_VERSION_MAJOR 0
#define SM_VERSION_MINOR 1
#define SM_VERSION_PATCH 0

#ifdef __cplusplus
extern "C" {
#endif

/// Version of the library linked, "major.minor.patch": the SM_VERSION_* of the headers it was
/// built with, to compare with those a program was compiled against.
SM_API const char* sm_version(void);

/// Status returned by the springmass functions that can fail in more than one way. SM_OK is
/// zero; every other value names one rule that was broken. sm_status_string() gives a short
/// generic text; the object involved (model, document, simulation) or an sm_error gives the
/// specific message. Functions that return a pointer return NULL on failure (those that take an
/// sm_error say why; sm_model_clone, sm_sparse_jacobian_create and sm_spring_jacobians_create
/// fail only for a NULL argument or a lack of memory); evaluation functions that return void or
/// a value do nothing, or return 0, for a NULL object or a NULL required array (NaN where their
/// comments say so: a NULL simulation's time, energies, dissipated energy, inputs' work and
/// inputs' power).
typedef enum sm_status {
	SM_OK = 0,
	SM_ERROR_INVALID_ARGUMENT,  ///< NULL pointer, unknown enum value or inconsistent option
	SM_ERROR_OUT_OF_MEMORY,     ///< an allocation failed; nothing was changed
	SM_ERROR_PARTICLE_INDEX,    ///< a particle index is out of range
	SM_ERROR_SPRING_INDEX,      ///< a spring index is out of range
	SM_ERROR_SELF_SPRING,       ///< a spring connects a particle to itself
	SM_ERROR_NOT_FINITE,        ///< a value is NaN or infinite where a finite one is required
	SM_ERROR_NEGATIVE,          ///< a value is negative where it must be >= 0, or not > 0 where it must be
	SM_ERROR_NONPOSITIVE_MASS,  ///< a particle mass is <= 0 (or below DBL_MIN, where 1 / mass overflows)
	SM_ERROR_ZERO_REST_LENGTH,  ///< a per-strain constant or a break strain on a spring of rest length 0
	SM_ERROR_FILE,              ///< a file cannot be read or written
	SM_ERROR_SYNTAX,            ///< a model file is not valid JSON (line and column in the message)
	SM_ERROR_SCHEMA,            ///< a model file breaks a rule of the format (path in the message)
	SM_ERROR_NOT_FOUND,         ///< a named parameter, particle or port does not exist
	SM_ERROR_SOLVER,            ///< the integrator or a linear solver failed (details in the message)
	SM_ERROR_NOT_CONVERGED,     ///< an iterative method stopped before meeting its tolerance
	SM_ERROR_TOPOLOGY,          ///< two models differ in particles or springs where they must match
	/// An advance used its max_steps internal steps, or its on_step hook stopped it, before its
	/// end: the state is valid at sm_simulation_time() and advancing again continues from it.
	SM_ERROR_STEP_LIMIT,
	SM_STATUS_COUNT
} sm_status;

/// Short, static, human-readable text for a status ("particle index out of range", ...).
SM_API const char* sm_status_string(sm_status status);

/// Capacity of the message buffer in sm_error [bytes].
#define SM_ERROR_MESSAGE_CAPACITY 512

/// Error report filled by functions that create objects (and so have no object to hold it).
/// Pass NULL where the detail is not needed. Every function that takes one fills it, on success
/// too (SM_OK and an empty message), so an earlier failure never stays in it. Messages, here and
/// in the objects' last-error texts, write numbers with a '.' whatever the program's locale.
typedef struct sm_error {
	sm_status status;                         ///< same value the function returned
	char message[SM_ERROR_MESSAGE_CAPACITY];  ///< specific message, NUL-terminated
} sm_error;

/// Capacity that sm_format_number needs [bytes], the terminating NUL included.
#define SM_NUMBER_TEXT_CAPACITY 32

/// Writes value as the shortest of 15, 16 and 17 significant digits ("%.*g") that reads back
/// (strtod) to exactly the same double: 0.03 as "0.03", not "0.029999999999999999"; NaN and
/// infinities as printf writes them. The decimal separator is "." whatever LC_NUMERIC the
/// program chose, as the model file's parser reads it. Used wherever springmass writes numbers
/// meant to be read back (model files, modelDescription.xml, the CSV of `springmass run`, messages).
SM_API void sm_format_number(double value, char text[SM_NUMBER_TEXT_CAPACITY]);

#ifdef __cplusplus
}
#endif

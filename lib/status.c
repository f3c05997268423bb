// Text of the status codes and of the version.
#include "springmass/base.h"

#define SM_STRINGIFY_(x) #x
#define SM_STRINGIFY(x) SM_STRINGIFY_(x)

const char* sm_version(void)
{
	return SM_STRINGIFY(SM_VERSION_MAJOR) "." SM_STRINGIFY(SM_VERSION_MINOR) "." SM_STRINGIFY(
	    SM_VERSION_PATCH);
}

const char* sm_status_string(sm_status status)
{
	switch (status) {
	case SM_OK: return "ok";
	case SM_ERROR_INVALID_ARGUMENT: return "invalid argument";
	case SM_ERROR_OUT_OF_MEMORY: return "out of memory";
	case SM_ERROR_PARTICLE_INDEX: return "particle index out of range";
	case SM_ERROR_SPRING_INDEX: return "spring index out of range";
	case SM_ERROR_SELF_SPRING: return "spring connects a particle to itself";
	case SM_ERROR_NOT_FINITE: return "value is not finite";
	case SM_ERROR_NEGATIVE: return "value is negative (or zero where it must be positive)";
	case SM_ERROR_NONPOSITIVE_MASS: return "mass is not positive";
	case SM_ERROR_ZERO_REST_LENGTH:
		return "per-strain constant or break strain on a spring of zero rest length";
	case SM_ERROR_FILE: return "file cannot be read or written";
	case SM_ERROR_SYNTAX: return "syntax error in model file";
	case SM_ERROR_SCHEMA: return "model file breaks a rule of the format";
	case SM_ERROR_NOT_FOUND: return "name not found";
	case SM_ERROR_SOLVER: return "solver failure";
	case SM_ERROR_NOT_CONVERGED: return "not converged";
	case SM_ERROR_TOPOLOGY: return "models differ in topology";
	case SM_ERROR_STEP_LIMIT: return "advance stopped before its end (step limit)";
	case SM_STATUS_COUNT: break;
	}
	return "unknown status";
}

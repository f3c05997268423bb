// What differs between the SUNDIALS versions springmass builds with: 6 (6.4.1, Debian 12's, which
// CI tests) and 7 (7.5.0 checked). The rest of the library and the tests use the names below.
#pragma once

#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#if SUNDIALS_VERSION_MAJOR >= 7

#include <float.h>

// SUNDIALS 7: a context takes a communicator (SUNComm, an int without MPI) and SUN_COMM_NULL for
// none; 6 took a pointer to one, NULL for none.
typedef SUNComm sm_sundials_comm;
#define SM_SUNDIALS_COMM_NULL SUN_COMM_NULL
// SUNDIALS 7 replaced the linear solvers' own success and out-of-memory codes with the shared ones.
#define SM_LS_SUCCESS SUN_SUCCESS
#define SM_LS_MEM_FAIL SUN_ERR_MEM_FAIL
// What a fused vector operation returns for fewer than one vector: SUNDIALS 7's own return
// SUN_ERR_ARG_OUTOFRANGE (in a build with its error checks; without them they do not check), 6's -1.
#define SM_NVEC_OUT_OF_RANGE SUN_ERR_ARG_OUTOFRANGE
// The significant digits of the times in CVODE's messages: SUNDIALS 7 writes them with
// SUN_FORMAT_G, "%.15g"; 6 with "%lg", 6 digits.
#define SM_CVODE_MESSAGE_DIGITS DBL_DIG

#else

typedef void* sm_sundials_comm;
#define SM_SUNDIALS_COMM_NULL NULL
#define SM_LS_SUCCESS SUNLS_SUCCESS
#define SM_LS_MEM_FAIL SUNLS_MEM_FAIL
#define SM_NVEC_OUT_OF_RANGE (-1)
#define SM_CVODE_MESSAGE_DIGITS 6

#endif

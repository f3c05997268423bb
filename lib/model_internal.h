// Internal layout of sm_model, shared by the files that evaluate it.
//
// Particles and springs are stored as structures of arrays so that the force loop streams
// through exactly the data it needs (the same arrays as the tightest hand-written loop).
#pragma once

#include "springmass/model.h"

#include <math.h>
#include <stdarg.h>
#include <stddef.h>

// The most particles, and the most springs, a model holds: INT32_MAX / 4 = 2^29 - 1, so that 3
// times a particle index (its first coordinate) and the sums of counts the solvers form stay
// within 32 bits.
#define SM_MODEL_MAX_ELEMENTS (INT32_MAX / 4)

struct sm_model {
	sm_model_def def;  // gravity [m/s^2], mass damping [1/s]

	// Particles (count, capacity).
	int32_t particle_count;
	int32_t particle_capacity;
	double* mass;      // [kg]
	double* position;  // initial positions, 3 per particle [m]
	double* velocity;  // initial velocities, 3 per particle [m/s]
	sm_particle_motion* motion;
	double* load;         // constant external forces, 3 per particle [N]
	int32_t load_count;   // particles with a load other than (0, 0, 0)
	int32_t* free_index;  // position among free particles, or -1
	int32_t free_count;

	// Springs (count, capacity). The resolved constants are what the force laws use.
	int32_t spring_count;
	int32_t spring_capacity;
	sm_spring_def* spring_def;  // as given, rest length resolved to metres
	int32_t* spring_a;          // first particle
	int32_t* spring_b;          // second particle
	double* rest_length;        // l0 [m] (0 for zero-length springs)
	double* stiffness;          // ks [N/m], 0 while disabled
	double* damping;            // kd [N s/m], 0 while disabled
	uint8_t* zero_length;       // 1 for SM_SPRING_ZERO_LENGTH
	uint8_t* enabled;           // 0 for a disabled (broken) spring

	char last_error[SM_ERROR_MESSAGE_CAPACITY];
};

// Every spring's Jacobian in factored form (model.h, sm_spring_jacobians; derivation in
// forces.c): per spring, SPRING_JACOBIAN_STRIDE doubles in spring order, one 64-byte record
//   u[3] (unit direction, 0 at the degenerate point) [1], z[3] [N/m], beta [N/m], kd [N s/m]
// with K = d f_a / d x_b = u z^T + beta I and D = d f_a / d v_b = kd u u^T.
#define SPRING_JACOBIAN_STRIDE 8

struct sm_spring_jacobians {
	int32_t particle_count;  // of the model the storage was made for
	int32_t spring_count;
	int evaluated;                // 0 until the first sm_model_forces_and_jacobians
	sm_jacobian_variant variant;  // of the last evaluation
	double* data;                 // SPRING_JACOBIAN_STRIDE per spring, 64-byte aligned
};

// The rule a break strain at or below SM_MIN_BREAK_STRAIN breaks, for a refusal's message: "break
// strain = V must be > 2^-53 = L: l0 (1 + break strain) would round to l0". Both numbers in full:
// with %g, 1.105e-16 "must be > 1.1e-16" would read as met.
#define SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY 160
void sm_break_strain_floor_text(double break_strain, char text[SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY]);

// vsnprintf in the C locale, whatever LC_NUMERIC the program chose: the text of every message
// (sm_model_fail, sm_error_set, ...), whose numbers then read the same in any locale.
int sm_vformat_c_locale(char* text, size_t size, const char* format, va_list args);
int sm_format_c_locale(char* text, size_t size, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

// Formats a message into model->last_error and returns status.
sm_status sm_model_fail(sm_model* model, sm_status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

// Sets err (if not NULL) to SM_OK and an empty message: what every public function taking an
// sm_error does first, so that a call that succeeds leaves no earlier failure in it.
void sm_error_clear(sm_error* err);

// Fills err (if not NULL) with status and a formatted message; returns status.
sm_status sm_error_set(sm_error* err, sm_status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

// Sets the motion of the particles marked in select[] (particle_count entries; NULL: those listed
// in particles[], count of them, valid indices) as sm_model_set_particle_motion sets one (a fixed
// particle's stored velocity becomes zero), numbering the free particles once for all: one call
// per particle would number them all again each time, quadratic in the model's size.
void sm_model_set_motions(sm_model* m, const bool* select, const int32_t* particles, int32_t count,
                          sm_particle_motion motion);

// Geometry of one spring at a configuration, shared by every force law and Jacobian.
//
// Both spring kinds are evaluated by the same formulas: a zero-length spring is a rest-length
// spring with l0 = 0, since ks (L - 0) u = ks d (see law_zero_length.h). The only special point
// is where u = d / L is undefined: inv_length is then 0, which makes u = 0 and so removes the
// elastic force of a degenerate rest-length spring and every damping force, as model.h states.
typedef struct spring_geometry {
	double d[3];        // x_b - x_a [m]
	double length;      // L = |d| [m]
	double inv_length;  // 1 / L, or 0 when L < SM_DEGENERATE_LENGTH_RATIO * l0 or L = 0 [1/m]
	double u[3];        // d / L, or 0 at the degenerate point [1]
	double dv[3];       // v_b - v_a [m/s]
	double rate;        // r = u . dv, rate of change of the length [m/s]
} spring_geometry;

static inline void spring_geometry_eval(const double* x, const double* v, int32_t a, int32_t b,
                                        double rest_length, spring_geometry* g)
{
	const double* xa = x + 3 * (size_t)a;
	const double* xb = x + 3 * (size_t)b;
	g->d[0] = xb[0] - xa[0];
	g->d[1] = xb[1] - xa[1];
	g->d[2] = xb[2] - xa[2];
	g->length = sqrt(g->d[0] * g->d[0] + g->d[1] * g->d[1] + g->d[2] * g->d[2]);
	const int regular = g->length > 0.0 && !(g->length < SM_DEGENERATE_LENGTH_RATIO * rest_length);
	const double inv = 1.0 / (regular ? g->length : 1.0);
	g->inv_length = regular ? inv : 0.0;
	for (int k = 0; k < 3; k++)
		g->u[k] = g->d[k] * g->inv_length;
	if (v != NULL) {
		const double* va = v + 3 * (size_t)a;
		const double* vb = v + 3 * (size_t)b;
		g->dv[0] = vb[0] - va[0];
		g->dv[1] = vb[1] - va[1];
		g->dv[2] = vb[2] - va[2];
	} else {
		g->dv[0] = g->dv[1] = g->dv[2] = 0.0;
	}
	g->rate = g->u[0] * g->dv[0] + g->u[1] * g->dv[1] + g->u[2] * g->dv[2];
}

// Per-spring Jacobian blocks K = d f_a / d x_b and D = d f_a / d v_b (row-major), the sum of
// the laws in law_rest_length.h (both kinds) and law_spring_damping.h. Defined in jacobian.c.
void sm_spring_blocks(const sm_model* model, int32_t spring, const double* x, const double* v,
                      sm_jacobian_variant variant, double K[9], double D[9]);

// sm_model_forces (the same numbers, bit for bit) and, from the same pass, the power the model
// dissipates, as sm_model_dissipated_power computes it but summed in another order [W]. x, v
// and f must be given. Defined in forces.c.
double sm_model_forces_and_power(const sm_model* model, const double* x, const double* v,
                                 const double* f_external, double* f);

// The terms of the energy that involve particle i: its kinetic and gravitational energy and the
// elastic energy of the springs at it, springs[0 .. count - 1] [J]. A move of particle i alone
// changes the energy (sm_model_energies) by the change of these terms, computed without the
// rest's round-off. x and v must be given. Defined in forces.c.
double sm_model_particle_energy(const sm_model* model, const double* x, const double* v, int32_t i,
                                const int32_t* springs, int32_t count);

// The elastic energy spring s holds with its particles a and b at xa and xb [J], as its term of
// sm_model_energies would be were it enabled (the spring's state is not looked at). What a break
// takes out of the elastic energy, computed from the spring alone: in time independent of the
// model's size, and without the round-off of the other springs' terms. Defined in forces.c.
double sm_model_spring_energy(const sm_model* model, int32_t s, const double xa[3], const double xb[3]);

// The force spring s exerts on its particle a with a at xa, va and b at xb, vb (m, m/s), f_a =
// (ks (L - l0) + kd r) u [N] as the spring loop has it (f_b = -f_a), enabled or not; returns the
// power its damping dissipates, kd r^2 [W]. Defined in forces.c.
double sm_model_spring_force(const sm_model* model, int32_t s, const double xa[3], const double xb[3],
                             const double va[3], const double vb[3], double f_a[3]);

// The springs' share of the forces, added to f, with at most `lanes` springs at a time (1, 2 or 4;
// fewer where the processor lacks SSE2 or AVX): damping if v is given, every spring's record of
// `variant` into jacobians if given, and their dissipated power added to *power if both v and
// power are given [W]. The public evaluations use the widest lanes the processor has; every width
// gives the same bits (the forces and records; the power with 2 and 4 lanes). Defined in forces.c,
// for the tests that check it.
void sm_model_spring_forces_lanes(const sm_model* model, const double* x, const double* v, double* f,
                                  sm_spring_jacobians* jacobians, sm_jacobian_variant variant, double* power,
                                  int lanes);

// sm_model_forces_and_power and, in the same pass over the springs, every spring's record of the
// definiteness-preserving Jacobian as sm_model_forces_and_jacobians stores it (the same numbers,
// bit for bit, as each of the two). v must be given. The right-hand side of a simulation whose
// linear solver will want the Jacobian at the same state (linear_solver_reduced.c).
double sm_model_forces_power_and_jacobians(const sm_model* model, const double* x, const double* v,
                                           const double* f_external, double* f,
                                           sm_spring_jacobians* jacobians);

// Gravity, mass damping and external forces (f_external NULL: none) on particles begin .. end - 1,
// written into their f as sm_model_forces starts it (v must be given); returns the power their
// mass damping dissipates [W]. With sm_spring_order_forces_and_jacobians, the pieces of
// sm_model_forces_power_and_jacobians that a caller may run on disjoint parts of the model at
// once (reduced_chunks.c). Defined in forces.c.
double sm_model_body_forces_range(const sm_model* model, const double* v, const double* f_external, double* f,
                                  int32_t begin, int32_t end);

// The springs in an order of the caller's: their particles and constants at positions 0, 1, ...
// (copies of the model's arrays, permuted).
typedef struct sm_spring_order {
	const int32_t* a;
	const int32_t* b;
	const double* rest_length;  // [m]
	const double* stiffness;    // [N/m]
	const double* damping;      // [N s/m]
} sm_spring_order;

// The springs at positions begin .. end - 1 of `order`: their forces, damping included, added to
// f, and their records of the definiteness-preserving Jacobian stored at the same positions of
// `records` (SPRING_JACOBIAN_STRIDE doubles each), by the loop of sm_model_forces_power_and_jacobians
// (the same numbers for each spring); returns their dissipated power [W]. Defined in forces.c.
double sm_spring_order_forces_and_jacobians(const sm_spring_order* order, int32_t begin, int32_t end,
                                            const double* x, const double* v, double* f, double* records);

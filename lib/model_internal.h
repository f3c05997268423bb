// Internal layout of sm_model, shared by the files that evaluate it.
//
// Particles and springs are stored as structures of arrays so that the force loop streams
// through exactly the data it needs (the same arrays as the tightest hand-written loop).
#pragma once

#include "springmass/model.h"

struct sm_model {
	sm_model_def def;  // gravity [m/s^2], mass damping [1/s]

	// Particles (count, capacity).
	int32_t particle_count;
	int32_t particle_capacity;
	double* mass;                    // [kg]
	double* position;                // initial positions, 3 per particle [m]
	double* velocity;                // initial velocities, 3 per particle [m/s]
	sm_particle_motion* motion;
	int32_t* free_index;             // position among free particles, or -1
	int32_t free_count;

	// Springs (count, capacity). The resolved constants are what the force laws use.
	int32_t spring_count;
	int32_t spring_capacity;
	sm_spring_def* spring_def;       // as given, rest length resolved to metres
	int32_t* spring_a;               // first particle
	int32_t* spring_b;               // second particle
	double* rest_length;             // l0 [m]
	double* stiffness;               // ks [N/m], 0 while disabled
	double* damping;                 // kd [N s/m], 0 while disabled
	uint8_t* zero_length;            // 1 for SM_SPRING_ZERO_LENGTH
	uint8_t* enabled;                // 0 for a disabled (broken) spring

	char last_error[SM_ERROR_MESSAGE_CAPACITY];
};

// Formats a message into model->last_error and returns status.
sm_status sm_model_fail(sm_model* model, sm_status status, const char* format, ...)
#if defined(__GNUC__)
	__attribute__((format(printf, 3, 4)))
#endif
	;

// Fills err (if not NULL) with status and a formatted message; returns status.
sm_status sm_error_set(sm_error* err, sm_status status, const char* format, ...)
#if defined(__GNUC__)
	__attribute__((format(printf, 3, 4)))
#endif
	;

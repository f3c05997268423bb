// A shared library built on springmass, as a plug-in or a language binding would be: the
// natural frequency of a mass on a spring, from springmass's modes (GSL's eigensolver).
#include <springmass/springmass.h>

// The natural frequency [Hz] of `mass` [kg] on a zero-length spring of `stiffness` [N/m] to a
// fixed anchor, no gravity; -1 on failure.
__attribute__((visibility("default"))) double frequency_of(double mass, double stiffness)
{
	sm_model_def world = sm_default_model_def();
	world.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&world, NULL);
	sm_particle_def anchor = sm_default_particle_def(), bob = sm_default_particle_def();
	anchor.motion = SM_PARTICLE_FIXED;
	bob.mass = mass;
	bob.position[0] = 1.0;
	sm_spring_def spring = sm_default_spring_def();
	spring.kind = SM_SPRING_ZERO_LENGTH;
	spring.a = 0;
	spring.b = 1;
	spring.stiffness = stiffness;
	double frequency = -1.0;
	sm_modes modes;
	if (model != NULL && sm_model_add_particle(model, &anchor, NULL) == SM_OK &&
	    sm_model_add_particle(model, &bob, NULL) == SM_OK &&
	    sm_model_add_spring(model, &spring, NULL) == SM_OK &&
	    sm_modes_compute(model, NULL, &modes, NULL) == SM_OK) {
		frequency = modes.frequency[0];
		sm_modes_release(&modes);
	}
	sm_model_destroy(model);
	return frequency;
}

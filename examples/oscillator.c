// A damped oscillator with the springmass C API: a 1 kg bob on a spring to a fixed anchor.
// Prints the bob's position next to the closed-form solution, and the energies.
#include <springmass/springmass.h>

#include <math.h>
#include <stdio.h>

int main(void)
{
	sm_model_def world = sm_default_model_def();
	world.gravity[2] = 0.0;  // no gravity [m/s^2]
	sm_model* model = sm_model_create(&world, NULL);
	if (model == NULL) {
		return 1;
	}

	sm_particle_def anchor = sm_default_particle_def();
	anchor.motion = SM_PARTICLE_FIXED;
	sm_particle_def bob = sm_default_particle_def();
	bob.mass = 1.0;         // [kg]
	bob.position[0] = 1.5;  // [m]
	int32_t a, b;
	sm_model_add_particle(model, &anchor, &a);
	sm_model_add_particle(model, &bob, &b);

	sm_spring_def spring = sm_default_spring_def();
	spring.a = a;
	spring.b = b;
	spring.rest_length = 1.0;  // [m]
	spring.stiffness = 40.0;   // [N/m]
	spring.damping = 0.4;      // [N s/m]
	if (sm_model_add_spring(model, &spring, NULL) != SM_OK) {
		fprintf(stderr, "%s\n", sm_model_last_error(model));
		sm_model_destroy(model);
		return 1;
	}

	sm_simulation_def options = sm_default_simulation_def();
	options.relative_tolerance = 1e-8;
	sm_error err;
	sm_simulation* sim = sm_simulation_create(model, &options, &err);
	if (sim == NULL) {
		fprintf(stderr, "%s\n", err.message);
		sm_model_destroy(model);
		return 1;
	}

	// Closed form: x(t) = 1 + 0.5 exp(-zeta w t) (cos(wd t) + zeta w / wd sin(wd t)).
	const double w = sqrt(40.0), zeta = 0.4 / (2.0 * w), wd = w * sqrt(1.0 - zeta * zeta);
	// Rows every 0.2 s up to 1 s. Nothing changes the inputs on the way, so CVODE may step on
	// past a row (up to 1 s) and the row is interpolated from its steps: the steps are those of
	// one advance to 1 s. sm_simulation_advance(sim, t) would end a step at every row instead.
	int status = 0;
	for (int k = 1; k <= 5; ++k) {
		double t = 0.2 * k;
		if (sm_simulation_advance_interpolated(sim, t, 1.0) != SM_OK) {
			fprintf(stderr, "%s\n", sm_simulation_last_error(sim));
			status = 1;
			break;
		}
		double x = sm_simulation_positions(sim)[3 * b];
		double exact = 1.0 + 0.5 * exp(-zeta * w * t) * (cos(wd * t) + zeta * w / wd * sin(wd * t));
		sm_energies e = sm_simulation_energies(sim);
		printf("t = %.1f s  x = %.6f m  exact = %.6f m  kinetic = %.4f J  elastic = %.4f J\n", t, x, exact,
		       e.kinetic, e.elastic);
		if (fabs(x - exact) > 1e-5) {
			status = 1;
		}
	}
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return status;
}

// A trampoline with the springmass C API: a square membrane held along its four edges sags
// under its own weight. The program finds the rest shape (statics), the lowest natural
// frequencies about it (modes), then drops the membrane from flat and simulates it, checking
// the energy balance on the way: kinetic + elastic + gravitational + dissipated energy stays at
// its initial value (zero).
#include <springmass/springmass.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

// Fixes every particle whose initial position lies in the box [lo, hi] [m].
static int hold(sm_model* model, double x0, double y0, double x1, double y1)
{
	const double lo[3] = {x0, y0, -1.0}, hi[3] = {x1, y1, 1.0};
	return sm_set_motion_in_box(model, lo, hi, SM_PARTICLE_FIXED, NULL) == SM_OK;
}

int main(void)
{
	// Once per program that runs the analyses: GSL's failures then come back as an sm_status
	// instead of aborting (GSL's handler is process-wide; see analysis.h).
	gsl_set_error_handler_off();
	const sm_model_def world = sm_default_model_def();  // gravity (0, 0, -9.81) m/s^2
	sm_model* model = sm_model_create(&world, NULL);
	if (model == NULL)
		return 1;

	// 21 x 21 particles on 1 m x 1 m, 2 kg in all. Constants per section, per unit width of the
	// membrane (stiffness [N/m], damping [N s/m]), and masses lumped from the cells around each
	// particle give the same membrane at any resolution: each spring stands for its share of
	// the sheet (structures.h). Per strain alone, a finer grid would be a stiffer membrane.
	sm_sheet_def sheet = sm_default_sheet_def();
	sheet.nu = sheet.nv = 21;
	sheet.mass = 2.0;
	sheet.mass_distribution = SM_MASS_LUMPED;
	sheet.structural.stiffness = 40000.0;
	sheet.structural.stiffness_scaling = SM_PER_SECTION;
	sheet.structural.damping = 20.0;
	sheet.structural.damping_scaling = SM_PER_SECTION;
	sheet.shear = sheet.structural;
	sheet.bend.stiffness = sheet.bend.damping = 0.0;  // a membrane: no bending springs
	sm_structure trampoline;
	const double e = 1e-6;  // margin of the boxes that select the edges [m]
	if (sm_add_sheet(model, &sheet, &trampoline) != SM_OK || !hold(model, -e, -e, e, 1 + e) ||
	    !hold(model, 1 - e, -e, 1 + e, 1 + e) || !hold(model, -e, -e, 1 + e, e) ||
	    !hold(model, -e, 1 - e, 1 + e, 1 + e)) {
		fprintf(stderr, "%s\n", sm_model_last_error(model));
		sm_model_destroy(model);
		return 1;
	}
	const int32_t n = sm_model_particle_count(model);
	const int32_t centre = sm_structure_particle(&trampoline, 10, 10, 0);
	int status = 0;

	// Rest shape. The supports carry the whole weight, their own particles' included.
	double* rest = malloc(3 * (size_t)n * sizeof *rest);
	sm_statics_result statics;
	sm_error err;
	if (rest == NULL || sm_statics_solve(model, NULL, rest, NULL, &statics, &err) != SM_OK) {
		fprintf(stderr, "statics: %s\n", rest ? err.message : "out of memory");
		free(rest);
		sm_model_destroy(model);
		return 1;
	}
	printf("rest shape: centre sags %.4f m, supports carry %.4f N (weight %.4f N), %d Newton iterations\n",
	       -rest[3 * centre + 2], statics.reaction_total[2], sheet.mass * 9.81, (int)statics.iterations);
	if (fabs(statics.reaction_total[2] - sheet.mass * 9.81) > 1e-6)
		status = 1;

	// Vibrations about the rest shape: the four lowest modes.
	sm_modes_def modes_def = sm_default_modes_def();
	modes_def.configuration = rest;
	modes_def.mode_count = 4;
	sm_modes modes;
	if (sm_modes_compute(model, &modes_def, &modes, &err) != SM_OK) {
		fprintf(stderr, "modes: %s\n", err.message);
		status = 1;
	} else {
		printf("lowest natural frequencies:");
		for (int32_t k = 0; k < modes.count; k++)
			printf(" %.3f Hz (damping ratio %.3f)", modes.frequency[k], modes.damping_ratio[k]);
		printf("\n");
		sm_modes_release(&modes);
	}

	// Dropped from flat. Energy balance: everything starts at zero (at rest, unstretched, z = 0),
	// so K + U + G + D stays zero up to the integration error. The springs stretch by about
	// 1e-4 m only and the membrane moves slowly, so the absolute tolerances must be tight for the
	// energies to come out right. The velocities' matters: with its default (1e-6 m/s) the
	// balance is off by 6.6e-5 J at t = 0.5 s, when the membrane passes near flat, 1.4 times the
	// 1e-3 |G| allowed below, and by 1.3e-4 J at t = 2 s (with both tolerances at their
	// defaults, it stays within 8.7e-4 |G|: allowed, by little). With these it stays within
	// 6e-6 |G| (measured, at the rows printed).
	sm_simulation_def options = sm_default_simulation_def();
	options.relative_tolerance = 1e-6;
	options.absolute_tolerance_position = 1e-9;  // [m]
	options.absolute_tolerance_velocity = 1e-8;  // [m/s]
	sm_simulation* sim = sm_simulation_create(model, &options, &err);
	if (sim == NULL) {
		fprintf(stderr, "simulation: %s\n", err.message);
		free(rest);
		sm_model_destroy(model);
		return 1;
	}
	printf("simulation with the %s solver:\n", sm_linear_solver_name(sm_simulation_solver(sim)));
	for (int k = 1; k <= 8 && status == 0; k++) {
		const double t = 0.25 * k;  // [s]
		if (sm_simulation_advance(sim, t) != SM_OK) {
			fprintf(stderr, "%s\n", sm_simulation_last_error(sim));
			status = 1;
			break;
		}
		const sm_energies en = sm_simulation_energies(sim);
		const double dissipated = sm_simulation_dissipated_energy(sim);
		const double balance = en.kinetic + en.elastic + en.gravity + dissipated;
		printf("t = %.2f s  centre z = %+.4f m  kinetic %.4f J  elastic %.4f J  gravity %+.4f J  dissipated "
		       "%.4f J  balance %+.1e J\n",
		       t, sm_simulation_positions(sim)[3 * centre + 2], en.kinetic, en.elastic, en.gravity,
		       dissipated, balance);
		if (!(fabs(balance) <= 1e-3 * fabs(en.gravity)))
			status = 1;
	}
	const sm_statistics stats = sm_simulation_statistics(sim);
	printf("%ld steps, %ld right-hand sides\n", (long)stats.steps, (long)stats.rhs_evaluations);
	sm_simulation_destroy(sim);
	free(rest);
	sm_model_destroy(model);
	return status;
}

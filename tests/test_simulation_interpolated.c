// sm_simulation_advance_interpolated: outputs interpolated from CVODE's steps, which run on to a
// later stop time. Checked against one advance to that stop time (the same steps and breaks, bit
// for bit), against closed forms (the damped oscillator, with and without a step force set
// between outputs; a spring pulled to its break), and for what it must leave alone.
#include "simulation_fixtures.h"
#include "simulation_internal.h"
#include "springmass/model_file.h"
#include "springmass/simulation.h"
#include "test_harness.h"

#include <stdlib.h>

#ifndef SPRINGMASS_MODELS_DIR
#error "SPRINGMASS_MODELS_DIR must name the bundled models"
#endif

// CVODE's own time t_n, on the simulation's time axis (CVODE counts from its last restart).
static double cvode_now(const sm_simulation* sim)
{
	double tn = 0.0;
	CVodeGetCurrentTime(sim->cvode, &tn);
	return sim->time_origin + tn;
}

// The oscillator of simulation_fixtures.h with a 1 kg bob, k = 40 N/m and damping ratio zeta,
// released from u = 0.2 m at rest: u'' + 2 zeta w0 u' + w0^2 u = F / m.
#define OSC_K 40.0
#define OSC_U0 0.2
static sm_model* damped_oscillator(double zeta, sm_particle_motion anchor_motion)
{
	return oscillator_anchored(1.0, OSC_K, 2.0 * zeta * sqrt(OSC_K), OSC_U0, anchor_motion);
}

// Free motion of u'' + 2 zeta w0 u' + w0^2 u = 0 (zeta < 1) from u(0) = u0, u'(0) = v0, at time
// tau: u = exp(-zeta w0 tau) (u0 cos(wd tau) + (v0 + zeta w0 u0) / wd sin(wd tau)).
static void free_motion(double zeta, double w0, double u0, double v0, double tau, double* u, double* v)
{
	const double wd = w0 * sqrt(1.0 - zeta * zeta), a = u0, b = (v0 + zeta * w0 * u0) / wd;
	const double e = exp(-zeta * w0 * tau), c = cos(wd * tau), s = sin(wd * tau);
	*u = e * (a * c + b * s);
	*v = e * (-zeta * w0 * (a * c + b * s) + wd * (-a * s + b * c));
}

// Rows every 0.01 s up to 5 s, interpolated, follow the closed form as closely as advancing to
// each row does (rtol 1e-10 on an amplitude of 0.2 m: the 1e-6 m bound, as for
// sm_simulation_advance), in fewer steps: the rows no longer end steps.
static int test_rows_follow_the_closed_form_in_fewer_steps(void)
{
	const double zeta = 0.1, w0 = sqrt(OSC_K);
	sm_model* model = damped_oscillator(zeta, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* interpolated = sm_simulation_create(model, &d, NULL);
	sm_simulation* stopped = sm_simulation_create(model, &d, NULL);
	ENSURE(interpolated != NULL && stopped != NULL);
	double worst = 0.0, worst_velocity = 0.0;
	for (int i = 1; i <= 500; i++) {
		const double t = 0.01 * i;
		ENSURE_STATUS(sm_simulation_advance_interpolated(interpolated, t, 5.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(stopped, t), SM_OK);
		ENSURE(sm_simulation_time(interpolated) == t);
		double u, v;
		free_motion(zeta, w0, OSC_U0, 0.0, t, &u, &v);
		worst = worst_of(worst, fabs(sm_simulation_positions(interpolated)[3] - 1.0 - u));
		worst_velocity = worst_of(worst_velocity, fabs(sm_simulation_velocities(interpolated)[3] - v));
	}
	ENSURE(worst <= 1e-6 && worst_velocity <= 1e-6 * w0);
	// The energy balance holds at an interpolated time too: the dissipated energy is part of
	// CVODE's state and interpolated with it (rtol 1e-10 of the 0.8 J at the start).
	const sm_energies e = sm_simulation_energies(interpolated);
	const double e0 = 0.5 * OSC_K * OSC_U0 * OSC_U0;
	ENSURE_NEAR(e.kinetic + e.elastic + sm_simulation_dissipated_energy(interpolated), e0, 1e-7 * e0);
	const int64_t steps = sm_simulation_statistics(interpolated).steps;
	// The same model advanced once to 5 s takes the interpolated run's steps exactly.
	sm_simulation* once = sm_simulation_create(model, &d, NULL);
	ENSURE(once != NULL);
	ENSURE_STATUS(sm_simulation_advance(once, 5.0), SM_OK);
	ENSURE(sm_simulation_statistics(once).steps == steps);
	ENSURE(memcmp(sm_simulation_positions(once), sm_simulation_positions(interpolated), 6 * sizeof(double)) ==
	       0);
	ENSURE(sm_simulation_statistics(stopped).steps > steps + 100);
	sm_simulation_destroy(once);
	sm_simulation_destroy(stopped);
	sm_simulation_destroy(interpolated);
	sm_model_destroy(model);
	return 0;
}

typedef struct run_record {
	int64_t steps;
	int32_t breaks;
	sm_break_event events[512];
	double* y;  // positions, velocities, dissipated energy
	int pending_seen;
	int64_t on_step_calls;
} run_record;

static bool count_step(void* context, double time)
{
	(void)time;
	((run_record*)context)->on_step_calls++;
	return true;
}

// The tearing cloth to t_end, one advance (dt = 0) or rows every dt interpolated.
static int tear(const sm_model* model, sm_linear_solver solver, double t_end, double dt, bool on_step,
                run_record* r)
{
	sm_simulation_def d = sm_default_simulation_def();
	d.solver = solver;
	d.relative_tolerance = 1e-4;
	d.absolute_tolerance_position = d.absolute_tolerance_velocity = 1e-6;
	if (on_step) {
		d.on_step = count_step;
		d.on_step_context = r;
	}
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	for (int pass = 0; pass < 2; pass++) {  // the second after a reset: the same run again
		if (dt == 0.0) {
			ENSURE_STATUS(sm_simulation_advance(sim, t_end), SM_OK);
		} else {
			const long rows = lround(t_end / dt);
			for (long k = 1; k <= rows; k++) {
				const double t = k == rows ? t_end : (double)k * dt;
				ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, t_end), SM_OK);
				ENSURE(sm_simulation_time(sim) == t);
				r->pending_seen += sim->break_pending;
			}
		}
		const int32_t n = sm_model_particle_count(model);
		const sm_statistics s = sm_simulation_statistics(sim);
		const int32_t breaks = sm_simulation_break_count(sim);
		ENSURE(breaks <= 512);
		if (pass == 0) {
			r->steps = s.steps;
			r->breaks = breaks;
			for (int32_t b = 0; b < breaks; b++)
				r->events[b] = sm_simulation_break(sim, b);
			r->y = malloc(sizeof(double) * (6 * (size_t)n + 1));
			ENSURE(r->y != NULL);
			memcpy(r->y, sm_simulation_positions(sim), 3 * (size_t)n * sizeof(double));
			memcpy(r->y + 3 * n, sm_simulation_velocities(sim), 3 * (size_t)n * sizeof(double));
			r->y[6 * n] = sm_simulation_dissipated_energy(sim);
			ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
		} else {
			ENSURE(s.steps == r->steps && breaks == r->breaks);
			ENSURE(memcmp(sm_simulation_positions(sim), r->y, 3 * (size_t)n * sizeof(double)) == 0);
		}
	}
	sm_simulation_destroy(sim);
	return 0;
}

// The bundled tearing cloth, torn for 0.8 s (about 60 springs break), with rows every 1 ms or
// 7 ms interpolated: the steps, the breaks (time and spring) and the final state are those of
// one advance to 0.8 s bit for bit, with every linear solver, with or without on_step, and again
// after a reset. Breaks that CVODE found past a row (in a step that ends after it) happen where
// CVODE found them, in the next advance.
static int test_rows_leave_the_run_of_one_advance(void)
{
	sm_error err;
	sm_document* doc = sm_document_load(SPRINGMASS_MODELS_DIR "/tearing_cloth.json", &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	const int32_t n = sm_model_particle_count(model);
	// KLU, six times slower here, to 0.3 s (11 breaks).
	const sm_linear_solver solvers[] = {SM_SOLVER_REDUCED_PCG, SM_SOLVER_REDUCED_CHOLMOD, SM_SOLVER_KLU};
	for (size_t k = 0; k < sizeof solvers / sizeof solvers[0]; k++) {
		const double t_end = solvers[k] == SM_SOLVER_KLU ? 0.3 : 0.8;
		run_record once = {0};
		ENSURE(tear(model, solvers[k], t_end, 0.0, false, &once) == 0);
		ENSURE(once.breaks >= (solvers[k] == SM_SOLVER_KLU ? 10 : 50));
		const double intervals[] = {1e-3, 7e-3};
		for (int i = 0; i < 2; i++) {
			run_record rows = {0};
			ENSURE(tear(model, solvers[k], t_end, intervals[i], i == 1, &rows) == 0);
			if (rows.steps != once.steps || rows.breaks != once.breaks)
				printf("  %s, rows every %g s: %lld steps, %d breaks; one advance: %lld, %d\n",
				       sm_linear_solver_name(solvers[k]), intervals[i], (long long)rows.steps,
				       (int)rows.breaks, (long long)once.steps, (int)once.breaks);
			ENSURE(rows.steps == once.steps && rows.breaks == once.breaks);
			for (int32_t b = 0; b < once.breaks; b++)
				ENSURE(rows.events[b].time == once.events[b].time &&
				       rows.events[b].spring == once.events[b].spring);
			ENSURE(memcmp(rows.y, once.y, (6 * (size_t)n + 1) * sizeof(double)) == 0);
			// Each of the two intervals left breaks pending past a row (about a third of them).
			ENSURE(rows.pending_seen > 0);
			ENSURE(i == 0 || rows.on_step_calls >= rows.steps);
			free(rows.y);
		}
		free(once.y);
	}
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return 0;
}

// A spring pulled at constant speed breaks at l0 (1 + strain) / speed = 0.1 / 0.37 s, between
// rows 10 ms apart, to CVODE's root precision (100 unit roundoffs of the time and step: 1e-12 s,
// as for sm_simulation_advance); and not before its time, at the row before it.
static int test_break_between_rows_at_its_analytic_time(void)
{
	sm_model* model = pulled_spring();
	ENSURE(model != NULL);
	sm_simulation_def d = sm_default_simulation_def();
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	const double speed = 0.37, x1[3] = {1.0, 0.0, 0.0}, v1[3] = {speed, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven(sim, 1, x1, v1), SM_OK);
	const double t_break = 0.1 / speed;
	for (int i = 1; i <= 100; i++) {
		const double t = 0.01 * i;
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, 1.0), SM_OK);
		ENSURE(sm_simulation_break_count(sim) == (t >= t_break ? 1 : 0));
		ENSURE(sm_model_spring_enabled(sm_simulation_model(sim), 0) == (t < t_break));
	}
	ENSURE(sm_simulation_break(sim, 0).spring == 0);
	ENSURE_NEAR(sm_simulation_break(sim, 0).time, t_break, 1e-12);
	// A break CVODE found past a row is dropped with the rest of its steps when the state is set
	// anew or the simulation reset; the spring then breaks where CVODE finds it again.
	for (int reset = 0; reset < 2; reset++) {
		ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
		ENSURE_STATUS(sm_simulation_set_driven(sim, 1, x1, v1), SM_OK);
		double t = 0.0;
		while (!sim->break_pending && t < t_break) {
			t += 1e-3;
			ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, 1.0), SM_OK);
		}
		ENSURE(sim->break_pending && sm_simulation_break_count(sim) == 0);
		if (reset) {
			ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
			ENSURE_STATUS(sm_simulation_set_driven(sim, 1, x1, v1), SM_OK);
		} else {
			double x[9], v[9];
			memcpy(x, sm_simulation_positions(sim), sizeof x);
			memcpy(v, sm_simulation_velocities(sim), sizeof v);
			ENSURE_STATUS(sm_simulation_set_state(sim, t, x, v), SM_OK);
		}
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.5, 1.0), SM_OK);
		ENSURE(sm_simulation_break_count(sim) == 1 && sm_simulation_break(sim, 0).spring == 0);
		ENSURE_NEAR(sm_simulation_break(sim, 0).time, t_break, 1e-12);
	}
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// The pulled spring of simulation_fixtures.h, its driven end given `speed` [m/s] along x by the
// model itself (no input set, so that every advance may step past its end).
static sm_model* pulled_by_its_model(double speed)
{
	sm_model* model = pulled_spring();
	sm_particle_def driven;
	if (model == NULL || sm_model_get_particle(model, 1, &driven) != SM_OK)
		return model;
	driven.velocity[0] = speed;
	if (sm_model_set_particle(model, 1, &driven) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// A break that CVODE finds exactly at the end of an advance happens in that advance, not the
// next: the pulled spring, its driven end given the speed 0.37 m/s by the model (no input set, so
// that every advance may step past its end), breaks where one advance to 1 s finds it; an advance
// to exactly that time ends with the spring broken there. The same steps, breaks and final state
// as the one advance, bit for bit.
static int test_a_break_at_the_end_time_happens_in_that_advance(void)
{
	sm_model* model = pulled_by_its_model(0.37);
	ENSURE(model != NULL);
	sm_simulation_def d = sm_default_simulation_def();
	sm_simulation* once = sm_simulation_create(model, &d, NULL);
	sm_simulation* rows = sm_simulation_create(model, &d, NULL);
	ENSURE(once != NULL && rows != NULL);
	ENSURE_STATUS(sm_simulation_advance(once, 1.0), SM_OK);
	ENSURE(sm_simulation_break_count(once) == 1);
	const double t_break = sm_simulation_break(once, 0).time;
	ENSURE_NEAR(t_break, 0.1 / 0.37, 1e-12);  // CVODE's root precision, as above
	ENSURE_STATUS(sm_simulation_advance_interpolated(rows, t_break, 1.0), SM_OK);
	ENSURE(sm_simulation_time(rows) == t_break);
	ENSURE(sm_simulation_break_count(rows) == 1 && !sm_model_spring_enabled(sm_simulation_model(rows), 0));
	ENSURE(!rows->break_pending);
	ENSURE(sm_simulation_break(rows, 0).time == t_break && sm_simulation_break(rows, 0).spring == 0);
	ENSURE_STATUS(sm_simulation_advance_interpolated(rows, 1.0, 1.0), SM_OK);
	ENSURE(sm_simulation_break_count(rows) == 1);
	ENSURE(sm_simulation_statistics(rows).steps == sm_simulation_statistics(once).steps);
	ENSURE(memcmp(sm_simulation_positions(rows), sm_simulation_positions(once), 9 * sizeof(double)) == 0);
	ENSURE(memcmp(sm_simulation_velocities(rows), sm_simulation_velocities(once), 9 * sizeof(double)) == 0);
	sm_simulation_destroy(rows);
	sm_simulation_destroy(once);
	sm_model_destroy(model);
	return 0;
}

// The oscillator released compressed (u = -0.2 m, zeta = 0.1) on a spring that breaks at strain
// 0.1: u rises through 0.1 m at t_b (0.374 s, found from the closed form by bisection) before
// its first maximum at pi / wd (0.146 m), and the bob then flies on at the 0.71 m/s it had.
// Rows every 0.1 ms up to 1 s, so that some fall inside the step in which CVODE finds the break
// (measured: 4.1 ms long, from 0.38 ms before t_b): those rows, at which the break is found but
// not yet due, are interpolated at their own time like the others; every row before t_b follows
// the oscillator, every row after it the flight from the state at t_b. rtol 1e-10 on 0.2 m: 1e-6 m
// as above (measured 2e-9 m), and the break time to that 1e-6 m over the bob's speed there.
static int test_rows_before_a_break_found_past_them_are_at_their_own_time(void)
{
	const double zeta = 0.1, w0 = sqrt(OSC_K), u0 = -0.2, strain = 0.1;
	sm_model* model = oscillator_anchored(1.0, OSC_K, 2.0 * zeta * w0, u0, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	sm_spring_def s;
	ENSURE_STATUS(sm_model_get_spring(model, 0, &s), SM_OK);
	s.break_strain = strain;  // l0 = 1 m: the spring breaks at u = 0.1 m
	ENSURE_STATUS(sm_model_set_spring(model, 0, &s), SM_OK);
	const double wd = w0 * sqrt(1.0 - zeta * zeta);
	double lo = 0.0, hi = acos(-1.0) / wd, u, v;  // u rises from u0 to its maximum over [0, pi / wd]
	for (int k = 0; k < 100; k++) {
		const double mid = 0.5 * (lo + hi);
		free_motion(zeta, w0, u0, 0.0, mid, &u, &v);
		if (u < strain)
			lo = mid;
		else
			hi = mid;
	}
	const double t_b = lo;
	double v_b;
	free_motion(zeta, w0, u0, 0.0, t_b, &u, &v_b);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	double worst = 0.0, worst_velocity = 0.0;
	int pending_rows = 0;
	for (int i = 1; i <= 10000; i++) {
		const double t = 1e-4 * i;
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, 1.0), SM_OK);
		pending_rows += sim->break_pending;
		ENSURE(sm_simulation_break_count(sim) == (t >= t_b ? 1 : 0));
		if (t < t_b) {
			free_motion(zeta, w0, u0, 0.0, t, &u, &v);
		} else {
			u = strain + v_b * (t - t_b);
			v = v_b;
		}
		worst = worst_of(worst, fabs(sm_simulation_positions(sim)[3] - 1.0 - u));
		worst_velocity = worst_of(worst_velocity, fabs(sm_simulation_velocities(sim)[3] - v));
	}
	if (!(worst <= 1e-6 && worst_velocity <= 1e-6 * w0))
		printf("  %g m, %g m/s from the closed form; %d rows with the break pending\n", worst, worst_velocity,
		       pending_rows);
	ENSURE(pending_rows > 0);
	ENSURE(worst <= 1e-6 && worst_velocity <= 1e-6 * w0);
	ENSURE(sm_simulation_break(sim, 0).spring == 0);
	ENSURE_NEAR(sm_simulation_break(sim, 0).time, t_b, 1e-6 / fabs(v_b));
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// An input set at a row while CVODE has stepped past it acts from that row on: CVODE restarts
// there (whatever restart_on_input_change says), and the next advance ends its last step at its
// end rather than step past it. A step force F, or the anchor moved by F / k,
// moves the bob's rest point to u = F / k, and the bob follows the closed form of the
// oscillator about it from the state it had at the row. Kept on without the restart, CVODE
// would have the force act only from the end of its step (here some 10 ms later: an error of
// F / m (10 ms)^2 / 2 = 5e-5 m). rtol 1e-10: 1e-6 m as above.
static int check_input_past_the_steps(bool driven)
{
	const double zeta = 0.1, w0 = sqrt(OSC_K), t_force = 0.5, force = 1.0;
	sm_model* model = damped_oscillator(zeta, driven ? SM_PARTICLE_DRIVEN : SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t_force, 2.0), SM_OK);
	double tn = cvode_now(sim);
	ENSURE(tn > t_force);  // CVODE has stepped past the row
	ENSURE(sm_simulation_statistics(sim).restarts == 0);
	const double shift = force / OSC_K;
	const double f[3] = {force, 0.0, 0.0}, moved[3] = {shift, 0.0, 0.0}, still[3] = {0.0, 0.0, 0.0};
	ENSURE_STATUS(driven ? sm_simulation_set_driven(sim, 0, moved, still)
	                     : sm_simulation_set_external_force(sim, 1, f),
	              SM_OK);
	double u1, v1;
	free_motion(zeta, w0, OSC_U0, 0.0, t_force, &u1, &v1);
	double worst = 0.0;
	for (int i = 1; i <= 150; i++) {
		const double t = t_force + 0.01 * i;
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, 2.0), SM_OK);
		// The advance after the change ends its last step at its end (within CVODE's stop-time
		// round-off), as the last one does at the stop time; the others, with the inputs
		// unchanged, step past.
		tn = cvode_now(sim);
		if (i == 1 || i == 150)
			ENSURE(tn <= t && tn > t - 1e-12);
		else
			ENSURE(tn > t);
		double u, v;
		free_motion(zeta, w0, u1 - shift, v1, t - t_force, &u, &v);
		worst = worst_of(worst, fabs(sm_simulation_positions(sim)[3] - 1.0 - (u + shift)));
	}
	if (!(worst <= 1e-6))
		printf("  %s: %g m from the closed form\n", driven ? "anchor moved" : "force", worst);
	ENSURE(worst <= 1e-6);
	ENSURE(sm_simulation_statistics(sim).restarts == 1);
	sm_simulation_destroy(sim);
	// An input small enough for CVODE's error control to take without a failure (1e-3 N, the
	// anchor moved by 1e-3 / k) gives the run of restart_on_input_change bit for bit: the same
	// restart at the row.
	double x[2][6];
	int64_t steps[2];
	for (int restart = 0; restart < 2; restart++) {
		sm_simulation_def dr = tight_def(SM_SOLVER_AUTO);
		dr.restart_on_input_change = restart;
		sim = sm_simulation_create(model, &dr, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t_force, 2.0), SM_OK);
		const double small[3] = {1e-3, 0.0, 0.0}, nudged[3] = {1e-3 / OSC_K, 0.0, 0.0};
		ENSURE_STATUS(driven ? sm_simulation_set_driven(sim, 0, nudged, still)
		                     : sm_simulation_set_external_force(sim, 1, small),
		              SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 2.0, 2.0), SM_OK);
		memcpy(x[restart], sm_simulation_positions(sim), sizeof x[restart]);
		steps[restart] = sm_simulation_statistics(sim).steps;
		ENSURE(sm_simulation_statistics(sim).restarts == 1);
		sm_simulation_destroy(sim);
	}
	ENSURE(steps[0] == steps[1] && memcmp(x[0], x[1], sizeof x[0]) == 0);
	sm_model_destroy(model);
	return 0;
}

static int test_input_set_past_the_steps_restarts_at_the_row(void)
{
	return check_input_past_the_steps(false) || check_input_past_the_steps(true);
}

// Inputs set again as they are are no change: the driven oscillator with its still anchor and
// the bob's zero force set anew before every row (10 ms apart, up to 2 s), as a master that sets
// every input at every point does, takes the steps of one advance to 2 s, with no restart, and
// ends in its state bit for bit.
static int test_inputs_set_unchanged_leave_the_run_of_one_advance(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* once = sm_simulation_create(model, &d, NULL);
	sm_simulation* rows = sm_simulation_create(model, &d, NULL);
	ENSURE(once != NULL && rows != NULL);
	ENSURE_STATUS(sm_simulation_advance(once, 2.0), SM_OK);
	const double zero[3] = {0.0, 0.0, 0.0};
	for (int i = 1; i <= 200; i++) {
		ENSURE_STATUS(sm_simulation_set_driven(rows, 0, zero, zero), SM_OK);
		ENSURE_STATUS(sm_simulation_set_external_force(rows, 1, zero), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(rows, i == 200 ? 2.0 : 0.01 * i, 2.0), SM_OK);
	}
	const sm_statistics s = sm_simulation_statistics(rows);
	ENSURE(s.restarts == 0 && s.steps == sm_simulation_statistics(once).steps);
	ENSURE(memcmp(sm_simulation_positions(rows), sm_simulation_positions(once), 6 * sizeof(double)) == 0);
	ENSURE(memcmp(sm_simulation_velocities(rows), sm_simulation_velocities(once), 6 * sizeof(double)) == 0);
	sm_simulation_destroy(rows);
	sm_simulation_destroy(once);
	sm_model_destroy(model);
	return 0;
}

// Whether two simulations of the two-particle oscillator differ: in steps, restarts, or the bits
// of their positions and velocities (1 when they do, after saying where).
static int runs_differ(sm_simulation* const sims[2])
{
	const sm_statistics quiet = sm_simulation_statistics(sims[0]), set = sm_simulation_statistics(sims[1]);
	ENSURE(set.restarts == quiet.restarts && set.steps == quiet.steps);
	ENSURE(memcmp(sm_simulation_positions(sims[1]), sm_simulation_positions(sims[0]), 6 * sizeof(double)) ==
	       0);
	ENSURE(memcmp(sm_simulation_velocities(sims[1]), sm_simulation_velocities(sims[0]), 6 * sizeof(double)) ==
	       0);
	return 0;
}

// A master that writes a moving anchor's motion at every row, on the path it follows (x0 + v t as
// the master computes it, which parts from the simulation's own sum in the last bits), changes no
// input: the run is the one without the calls, bit for bit, with no restart. The calls re-based
// the path on the given position, and the state at 2 s differed in its last bits.
static int test_a_motion_set_on_its_own_path_changes_no_input(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sims[2] = {sm_simulation_create(model, &d, NULL), sm_simulation_create(model, &d, NULL)};
	ENSURE(sims[0] != NULL && sims[1] != NULL);
	const double start[3] = {0.0, 0.0, 0.0}, v[3] = {0.3, 0.1, 0.0};
	for (int k = 0; k < 2; k++) {
		ENSURE_STATUS(sm_simulation_set_driven(sims[k], 0, start, v), SM_OK);
		for (int i = 1; i <= 200; i++) {
			const double t = i == 200 ? 2.0 : 0.01 * i;
			ENSURE_STATUS(sm_simulation_advance_interpolated(sims[k], t, 2.0), SM_OK);
			const double x[3] = {v[0] * t, v[1] * t, 0.0};
			if (k == 1)
				ENSURE_STATUS(sm_simulation_set_driven(sims[k], 0, x, v), SM_OK);
		}
	}
	const int differ = runs_differ(sims);
	sm_simulation_destroy(sims[0]);
	sm_simulation_destroy(sims[1]);
	sm_model_destroy(model);
	ENSURE(!differ);
	return 0;
}

// A held force and a driven velocity given again at every row as a master interpolates a constant
// signal between two samples, w0 v + w1 v with w0 = (t1 - t) / (t1 - t0) and w1 = 1 - w0 (fmpy's
// input tables), are the held values to within round-off: an ulp off at some rows (1.3 N and 1.3
// m/s here: at 10 of the 200 rows), which is no input change, as a ramp within round-off is none.
// The run is the one in which they were set once, bit for bit, with its steps and restarts. Every
// such row restarted CVODE, and the next one again: 21 restarts and 1123 steps against 1 and 549.
static int test_held_inputs_interpolated_by_a_master_change_no_input(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sims[2] = {sm_simulation_create(model, &d, NULL), sm_simulation_create(model, &d, NULL)};
	ENSURE(sims[0] != NULL && sims[1] != NULL);
	const double held = 1.3, t0 = 0.0, t1 = 2.0, zero[3] = {0.0, 0.0, 0.0};
	const double force[3] = {held, 0.0, 0.0}, v[3] = {held, 0.0, 0.0};
	int off = 0;
	for (int k = 0; k < 2; k++) {
		ENSURE_STATUS(sm_simulation_set_driven(sims[k], 0, zero, v), SM_OK);
		ENSURE_STATUS(sm_simulation_set_external_force(sims[k], 1, force), SM_OK);
		for (int i = 1; i <= 200; i++) {
			const double t = i == 200 ? 2.0 : 0.01 * i;
			ENSURE_STATUS(sm_simulation_advance_interpolated(sims[k], t, 2.0), SM_OK);
			const double w0 = (t1 - t) / (t1 - t0), w1 = 1.0 - w0, given = w0 * held + w1 * held;
			const double f[3] = {given, 0.0, 0.0}, u[3] = {given, 0.0, 0.0}, x[3] = {held * t, 0.0, 0.0};
			off += k == 1 && given != held;
			if (k == 1) {
				ENSURE_STATUS(sm_simulation_set_driven(sims[k], 0, x, u), SM_OK);
				ENSURE_STATUS(sm_simulation_set_external_force(sims[k], 1, f), SM_OK);
			}
		}
	}
	ENSURE(off > 0);
	const int differ = runs_differ(sims);
	sm_simulation_destroy(sims[0]);
	sm_simulation_destroy(sims[1]);
	sm_model_destroy(model);
	ENSURE(!differ);
	return 0;
}

// A force on a held particle moves nothing: setting it, changed at every row, is no input change
// (no restart; the run of one advance, bit for bit). It restarted CVODE at every row.
static int test_a_force_on_a_held_particle_changes_no_input(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* once = sm_simulation_create(model, &d, NULL);
	sm_simulation* rows = sm_simulation_create(model, &d, NULL);
	ENSURE(once != NULL && rows != NULL);
	ENSURE_STATUS(sm_simulation_advance(once, 1.0), SM_OK);
	for (int i = 1; i <= 100; i++) {
		const double f[3] = {0.1 * i, -1.0, 2.0};
		ENSURE_STATUS(sm_simulation_set_external_force(rows, 0, f), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(rows, i == 100 ? 1.0 : 0.01 * i, 1.0), SM_OK);
	}
	ENSURE(sm_simulation_statistics(rows).restarts == 0);
	ENSURE(memcmp(sm_simulation_positions(rows), sm_simulation_positions(once), 6 * sizeof(double)) == 0);
	sm_simulation_destroy(rows);
	sm_simulation_destroy(once);
	sm_model_destroy(model);
	return 0;
}

// A row just after a spring break (1e-12 s, 1e-9 s after it) leaves the run of one advance to the
// stop time, bit for bit: CVODE's restart at the break sizes its first step from the stop time as
// one advance does, not from the row (a cap of a million times the row's interval made it take
// 311 steps instead of 308).
static int test_a_row_just_after_a_break_leaves_the_run_of_one_advance(void)
{
	sm_model* model = pulled_by_its_model(0.25);  // breaks at 0.1 / 0.25 = 0.4 s
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* once = sm_simulation_create(model, &d, NULL);
	ENSURE(once != NULL);
	ENSURE_STATUS(sm_simulation_advance(once, 1.0), SM_OK);
	ENSURE(sm_simulation_break_count(once) == 1);
	const double t_break = sm_simulation_break(once, 0).time;
	ENSURE_NEAR(t_break, 0.4, 1e-9);
	const double gaps[] = {1e-12, 1e-9, 1e-6};
	for (size_t k = 0; k < sizeof gaps / sizeof gaps[0]; k++) {
		sm_simulation* rows = sm_simulation_create(model, &d, NULL);
		ENSURE(rows != NULL);
		ENSURE_STATUS(sm_simulation_advance_interpolated(rows, t_break + gaps[k], 1.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(rows, 1.0, 1.0), SM_OK);
		ENSURE(sm_simulation_statistics(rows).steps == sm_simulation_statistics(once).steps);
		ENSURE(memcmp(sm_simulation_positions(rows), sm_simulation_positions(once), 9 * sizeof(double)) == 0);
		sm_simulation_destroy(rows);
	}
	sm_simulation_destroy(once);
	sm_model_destroy(model);
	return 0;
}

// A stop time far beyond the rows (a master's 1e28 s or the largest double for "no end") sizes no
// step of the run: CVODE sized its first step from it, at least 100 eps of it (2e14 s for 1e28 s),
// and failed at t = 0 every time. The rows are those of a stop time 1e9 s ahead, bit for bit, and
// on the closed form to 1e-8 m (rtol 1e-10 of 0.2 m, and 2 s of stepping).
static int test_a_far_stop_time_sizes_no_step(void)
{
	const double zeta = 0.1, w0 = sqrt(OSC_K), stops[] = {1e9, 1e28, DBL_MAX};
	sm_model* model = damped_oscillator(zeta, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	double first[6];
	for (size_t k = 0; k < sizeof stops / sizeof stops[0]; k++) {
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		for (int i = 1; i <= 200; i++)
			ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.01 * i, stops[k]), SM_OK);
		double u, v;
		free_motion(zeta, w0, OSC_U0, 0.0, sm_simulation_time(sim), &u, &v);
		ENSURE_NEAR(sm_simulation_positions(sim)[3], 1.0 + u, 1e-8);
		if (k == 0)
			memcpy(first, sm_simulation_positions(sim), sizeof first);
		ENSURE(memcmp(sm_simulation_positions(sim), first, sizeof first) == 0);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// Sets the inputs of the driven oscillator at a row: the anchor moved by 1e-3 N / k (2.5e-5 m) or a
// 1e-3 N force on the bob, as `change` says, and then, when `also_held` says so, the other input
// again as it is (the anchor where it is, still; no force): what a master does that sets every
// input at every point, only some of them changed.
enum { MOVE_ANCHOR = 1, PUSH_BOB = 2 };
static int set_inputs(sm_simulation* sim, int change, bool also_held)
{
	const double nudged[3] = {1e-3 / OSC_K, 0.0, 0.0}, push[3] = {1e-3, 0.0, 0.0}, zero[3] = {0.0, 0.0, 0.0};
	if (change == MOVE_ANCHOR) {
		ENSURE_STATUS(sm_simulation_set_driven(sim, 0, nudged, zero), SM_OK);
		if (also_held)
			ENSURE_STATUS(sm_simulation_set_external_force(sim, 1, zero), SM_OK);
	} else {
		ENSURE_STATUS(sm_simulation_set_external_force(sim, 1, push), SM_OK);
		if (also_held)
			ENSURE_STATUS(sm_simulation_set_driven(sim, 0, zero, zero), SM_OK);
	}
	return 0;
}

// An input changed at a row makes the next advance end its last step at its end, whatever other
// inputs are set after it unchanged: the run with the unchanged input set again is the run
// without it, bit for bit (the same steps and states), for a moved anchor followed by an
// unchanged force and a force followed by an unchanged anchor. The advance after that, the
// inputs unchanged, steps past its end again.
static int test_an_unchanged_input_set_after_a_changed_one_keeps_the_change(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	const int changes[] = {MOVE_ANCHOR, PUSH_BOB};
	for (size_t c = 0; c < sizeof changes / sizeof changes[0]; c++) {
		double x[2][6];
		int64_t steps[2];
		for (int held = 0; held < 2; held++) {
			sm_simulation* sim = sm_simulation_create(model, &d, NULL);
			ENSURE(sim != NULL);
			ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.5, 2.0), SM_OK);
			ENSURE(set_inputs(sim, changes[c], held) == 0);
			for (int i = 1; i <= 150; i++) {
				const double t = 0.5 + 0.01 * i;
				ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t, 2.0), SM_OK);
				const double tn = cvode_now(sim);
				if (i == 1)
					ENSURE(tn <= t && tn > t - 1e-12);  // CVODE's stop-time round-off, as above
				else if (i == 2)
					ENSURE(tn > t);
			}
			memcpy(x[held], sm_simulation_positions(sim), sizeof x[held]);
			steps[held] = sm_simulation_statistics(sim).steps;
			sm_simulation_destroy(sim);
		}
		ENSURE(steps[0] == steps[1] && memcmp(x[0], x[1], sizeof x[0]) == 0);
	}
	sm_model_destroy(model);
	return 0;
}

// An advance to the current time does nothing, also to what the inputs changed since the last
// advance mean for the next: after a force changed at a row, the next advance still ends its last
// step at its end (CVODE's time there, to its stop-time round-off), and the run with such an
// advance (plain or interpolated) in between is the run without it, bit for bit. It took the
// change as seen, and the next advance stepped past its end.
static int test_an_advance_to_the_current_time_keeps_a_changed_input(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	double x[3][6];
	int64_t steps[3];
	for (int idle = 0; idle < 3; idle++) {
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.5, 2.0), SM_OK);
		ENSURE(set_inputs(sim, PUSH_BOB, false) == 0);
		if (idle == 1)
			ENSURE_STATUS(sm_simulation_advance(sim, 0.5), SM_OK);
		else if (idle == 2)
			ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.5, 2.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.51, 2.0), SM_OK);
		double tn = cvode_now(sim);
		ENSURE(tn <= 0.51 && tn > 0.51 - 1e-12);
		memcpy(x[idle], sm_simulation_positions(sim), sizeof x[idle]);
		steps[idle] = sm_simulation_statistics(sim).steps;
		sm_simulation_destroy(sim);
	}
	for (int idle = 1; idle < 3; idle++)
		ENSURE(steps[idle] == steps[0] && memcmp(x[idle], x[0], sizeof x[0]) == 0);
	sm_model_destroy(model);
	return 0;
}

// A plain advance to a time CVODE has already passed interpolates, with no step and no
// restart, the value an interpolated advance gives; one past CVODE's time steps on. With the
// on_step hook too, which is told of no step then (CVODE, asked for one more step, would take it
// past the time, where it has already been).
static int test_plain_advance_within_the_steps_interpolates(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	for (int hooked = 0; hooked < 2; hooked++) {
		run_record calls = {0};
		sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
		if (hooked) {
			d.on_step = count_step;
			d.on_step_context = &calls;
		}
		sm_simulation* a = sm_simulation_create(model, &d, NULL);
		sm_simulation* b = sm_simulation_create(model, &d, NULL);
		ENSURE(a != NULL && b != NULL);
		ENSURE_STATUS(sm_simulation_advance_interpolated(a, 0.3, 2.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(b, 0.3, 2.0), SM_OK);
		double tn = cvode_now(a);
		ENSURE(tn > 0.3);
		const double t = 0.5 * (0.3 + tn);
		const sm_statistics before = sm_simulation_statistics(a);
		const int64_t calls_before = calls.on_step_calls;
		ENSURE_STATUS(sm_simulation_advance(a, t), SM_OK);
		const sm_statistics after = sm_simulation_statistics(a);
		ENSURE(after.steps == before.steps && after.restarts == 0);
		ENSURE(after.rhs_evaluations == before.rhs_evaluations && calls.on_step_calls == calls_before);
		ENSURE_STATUS(sm_simulation_advance_interpolated(b, t, 2.0), SM_OK);
		ENSURE(sm_simulation_time(a) == t);
		ENSURE(memcmp(sm_simulation_positions(a), sm_simulation_positions(b), 6 * sizeof(double)) == 0);
		ENSURE(memcmp(sm_simulation_velocities(a), sm_simulation_velocities(b), 6 * sizeof(double)) == 0);
		ENSURE_STATUS(sm_simulation_advance(a, 1.0), SM_OK);
		ENSURE(sm_simulation_time(a) == 1.0 && sm_simulation_statistics(a).steps > after.steps);
		sm_simulation_destroy(b);
		sm_simulation_destroy(a);
	}
	sm_model_destroy(model);
	return 0;
}

// max_steps holds for an advance that steps past its end as for one that does not: allowed 10
// steps, the oscillator advanced to 1 s with the stop time 2 s (some 190 steps at rtol 1e-10)
// fails with CV_TOO_MUCH_WORK after exactly 10, where a plain advance to 2 s with the same limit
// stops: the same steps (CVODE sizes its first from the time it is given, 2 s in both), the same
// time and state, bit for bit. Both go on alike from there, 10 steps per advance.
static int test_max_steps_holds_when_stepping_past_the_end(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	d.max_steps = 10;
	sm_simulation* past = sm_simulation_create(model, &d, NULL);
	sm_simulation* plain = sm_simulation_create(model, &d, NULL);
	ENSURE(past != NULL && plain != NULL);
	for (int attempt = 1; attempt <= 3; attempt++) {
		ENSURE_STATUS(sm_simulation_advance_interpolated(past, 1.0, 2.0), SM_ERROR_STEP_LIMIT);
		ENSURE_STATUS(sm_simulation_advance(plain, 2.0), SM_ERROR_STEP_LIMIT);
		ENSURE(strstr(sm_simulation_last_error(past), "CV_TOO_MUCH_WORK") != NULL);
		ENSURE(sm_simulation_statistics(past).steps == 10 * attempt);
		ENSURE(sm_simulation_statistics(plain).steps == 10 * attempt);
		ENSURE(sm_simulation_time(past) == sm_simulation_time(plain) && sm_simulation_time(plain) < 1.0);
		const size_t bytes = 6 * sizeof(double);
		ENSURE(memcmp(sm_simulation_positions(past), sm_simulation_positions(plain), bytes) == 0);
		ENSURE(memcmp(sm_simulation_velocities(past), sm_simulation_velocities(plain), bytes) == 0);
	}
	sm_simulation_destroy(plain);
	sm_simulation_destroy(past);
	sm_model_destroy(model);
	return 0;
}

// An interval below the time resolution (4 eps max(1 s, |t|), 8.9e-16 s at t = 1 s) is one explicit
// Euler step for an interpolated advance too, also when an input changed, so that CVODE would end
// its last step at the end time: there a restart (restart_on_input_change) failed with
// CV_TOO_CLOSE, as plain advances did before they took such steps. With and without on_step, the
// state is the one sm_simulation_advance gives to the same time, bit for bit (both the same
// Euler step), and the run then goes on.
static int test_an_interval_below_the_time_resolution_after_a_changed_input(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	const double push[3] = {1.0, 0.0, 0.0}, t_end = 1.0 + 4e-16;
	for (int hooked = 0; hooked < 2; hooked++) {
		run_record r = {0};
		sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
		d.restart_on_input_change = true;
		if (hooked) {
			d.on_step = count_step;
			d.on_step_context = &r;
		}
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		sm_simulation* plain = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL && plain != NULL);
		ENSURE_STATUS(sm_simulation_advance(sim, 1.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(plain, 1.0), SM_OK);
		ENSURE_STATUS(sm_simulation_set_external_force(sim, 1, push), SM_OK);
		ENSURE_STATUS(sm_simulation_set_external_force(plain, 1, push), SM_OK);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, t_end, 2.0), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(plain, t_end), SM_OK);
		ENSURE(sm_simulation_time(sim) == t_end && sm_simulation_time(plain) == t_end);
		ENSURE(memcmp(sm_simulation_positions(sim), sm_simulation_positions(plain), 6 * sizeof(double)) == 0);
		ENSURE(memcmp(sm_simulation_velocities(sim), sm_simulation_velocities(plain), 6 * sizeof(double)) ==
		       0);
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 1.5, 2.0), SM_OK);
		ENSURE(sm_simulation_time(sim) == 1.5);
		sm_simulation_destroy(plain);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// A stop time that is not finite or lies before the end time is refused, as is an end time
// before the current time, with nothing changed and the message naming the times.
static int test_bad_times_are_refused(void)
{
	sm_model* model = damped_oscillator(0.1, SM_PARTICLE_FIXED);
	ENSURE(model != NULL);
	sm_simulation_def d = sm_default_simulation_def();
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.25, 1.0), SM_OK);
	double x[6];
	memcpy(x, sm_simulation_positions(sim), sizeof x);
	const int64_t steps = sm_simulation_statistics(sim).steps;
	const double bad[][2] = {{0.5, 0.4}, {0.5, NAN}, {0.5, INFINITY},
	                         {0.1, 1.0}, {NAN, 1.0}, {INFINITY, INFINITY}};
	for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
		ENSURE_STATUS(sm_simulation_advance_interpolated(sim, bad[k][0], bad[k][1]),
		              SM_ERROR_INVALID_ARGUMENT);
		ENSURE(strstr(sm_simulation_last_error(sim), k < 3 ? "stop time" : "end time") != NULL);
		ENSURE(sm_simulation_time(sim) == 0.25 && sm_simulation_statistics(sim).steps == steps);
		ENSURE(memcmp(sm_simulation_positions(sim), x, sizeof x) == 0);
	}
	ENSURE(strstr(sm_simulation_last_error(sim), "advance_interpolated") != NULL);
	ENSURE_STATUS(sm_simulation_advance_interpolated(NULL, 1.0, 1.0), SM_ERROR_INVALID_ARGUMENT);
	// The stop time equal to the end time is a plain advance; to the current time, nothing.
	ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.25, 0.25), SM_OK);
	ENSURE(sm_simulation_statistics(sim).steps == steps);
	ENSURE_STATUS(sm_simulation_advance_interpolated(sim, 0.5, 0.5), SM_OK);
	ENSURE(sm_simulation_time(sim) == 0.5);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_rows_follow_the_closed_form_in_fewer_steps);
	RUN_TEST(test_rows_leave_the_run_of_one_advance);
	RUN_TEST(test_break_between_rows_at_its_analytic_time);
	RUN_TEST(test_a_break_at_the_end_time_happens_in_that_advance);
	RUN_TEST(test_rows_before_a_break_found_past_them_are_at_their_own_time);
	RUN_TEST(test_input_set_past_the_steps_restarts_at_the_row);
	RUN_TEST(test_inputs_set_unchanged_leave_the_run_of_one_advance);
	RUN_TEST(test_a_motion_set_on_its_own_path_changes_no_input);
	RUN_TEST(test_held_inputs_interpolated_by_a_master_change_no_input);
	RUN_TEST(test_a_force_on_a_held_particle_changes_no_input);
	RUN_TEST(test_a_far_stop_time_sizes_no_step);
	RUN_TEST(test_a_row_just_after_a_break_leaves_the_run_of_one_advance);
	RUN_TEST(test_an_unchanged_input_set_after_a_changed_one_keeps_the_change);
	RUN_TEST(test_an_advance_to_the_current_time_keeps_a_changed_input);
	RUN_TEST(test_plain_advance_within_the_steps_interpolates);
	RUN_TEST(test_max_steps_holds_when_stepping_past_the_end);
	RUN_TEST(test_bad_times_are_refused);
	RUN_TEST(test_an_interval_below_the_time_resolution_after_a_changed_input);
	return TEST_SUMMARY();
}

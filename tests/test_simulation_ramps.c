// Inputs that change along a step: external forces that ramp (sm_simulation_set_external_force_ramp)
// and driven particles that accelerate (sm_simulation_set_driven_accelerating), as a co-simulation
// master extrapolates an input from its value and derivative. Checked against closed forms (an
// oscillator pushed by a ramp, one dragged by an accelerating anchor, a spring pulled to its break),
// for what a caller continuing them does, and through snapshots and resets.
#include "simulation_fixtures.h"
#include "springmass/simulation.h"
#include "test_harness.h"

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define OSC_M 1.0
#define OSC_K 40.0

// The undamped oscillator (1 kg, 40 N/m, at rest at its rest length) pushed along the spring by
// f(t) = f0 + r t from t = 0: m u'' + k u = f0 + r t, u(0) = u'(0) = 0, so
// u = (f0 + r t) / k - f0 / k cos(w t) - r / (k w) sin(w t), w = sqrt(k / m); the bob's force is
// f0 + r t - k u. Every linear solver (each evaluates forces on its own path). At rtol 1e-10 on
// displacements of 0.1 m the global error stays near 1e-9 m over 2 s (measured up to 6.7e-10 m):
// 1e-7 m, and on the force k times that: 4e-6 N.
static int test_ramped_force_pushes_oscillator_as_closed_form(void)
{
	const double f0 = 0.5, r = 2.0, w = sqrt(OSC_K / OSC_M);
	sm_model* model = oscillator(OSC_M, OSC_K, 0.0, 0.0);
	ENSURE(model != NULL);
	const sm_linear_solver solvers[] = {SM_SOLVER_DENSE, SM_SOLVER_KLU, SM_SOLVER_REDUCED_PCG,
	                                    SM_SOLVER_REDUCED_CHOLMOD};
	for (size_t s = 0; s < sizeof solvers / sizeof solvers[0]; s++) {
		const sm_simulation_def d = tight_def(solvers[s]);
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		const double force[3] = {f0, 0.0, 0.0}, rate[3] = {r, 0.0, 0.0};
		ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, force, rate), SM_OK);
		double worst_x = 0.0, worst_f = 0.0, f[6];
		for (int i = 1; i <= 20; i++) {
			const double t = 0.1 * i;
			ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
			const double push = f0 + r * t;
			const double u = push / OSC_K - f0 / OSC_K * cos(w * t) - r / (OSC_K * w) * sin(w * t);
			worst_x = worst_of(worst_x, fabs(sm_simulation_positions(sim)[3] - (1.0 + u)));
			sm_simulation_forces(sim, f);
			worst_f = worst_of(worst_f, fabs(f[3] - (push - OSC_K * u)));
		}
		printf("  %s: max |x - closed form| = %.3g m, max |force - closed form| = %.3g N\n",
		       sm_linear_solver_name(solvers[s]), worst_x, worst_f);
		ENSURE(worst_x <= 1e-7);
		ENSURE(worst_f <= 4e-6);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// A force that turns at every call keeps CVODE's history under the default options: a master that
// samples 0.1 sin(t) N every 1 ms and ramps through the samples (each call the force the last ramp
// reached, to round-off, with the slope to the next sample) keeps the right-hand side continuous,
// only its slope changing. Restarting at each call, as every change did before, left the undamped
// oscillator (1 kg, 40 N/m, started 0.1 m out) 4.5e-3 m off the exact response after 10 s, in
// 30 015 steps: each restart starts BDF again at first order and costs about rtol of the motion.
// With the history kept: 5.4e-8 m in 10 004 steps at rtol 1e-6 (measured; 5e-7 m). On each
// stretch the exact response is u = F(t) / k + A cos(w s) + B sin(w s), F linear in s. The same
// samples held jump at every call, by at most 1e-4 N: over the 1 ms to the next call 1e-7 m/s on
// the 1 kg bob, within the velocity tolerance of 1e-6 m/s, so the history carries them too:
// 2.2e-6 m off (measured; 2e-5 m), where a restart at each left it 4.5e-3 m off as well.
static int test_a_force_that_turns_at_every_call_keeps_the_history(void)
{
	const double w = sqrt(OSC_K / OSC_M), h = 1e-3;
	const int calls = 10000;
	sm_model* model = oscillator(OSC_M, OSC_K, 0.0, 0.1);
	ENSURE(model != NULL);
	for (int held = 0; held <= 1; held++) {
		sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
		ENSURE(sim != NULL);
		double u = 0.1, v = 0.0;  // the exact displacement [m] and velocity [m/s]
		for (int k = 0; k < calls; k++) {
			const double f0 = 0.1 * sin(k * h), f1 = 0.1 * sin((k + 1) * h);
			const double rate = held ? 0.0 : (f1 - f0) / h;
			const double force[3] = {f0, 0.0, 0.0}, slope[3] = {rate, 0.0, 0.0};
			ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, force, slope), SM_OK);
			ENSURE_STATUS(sm_simulation_advance(sim, (k + 1) * h), SM_OK);
			const double a = u - f0 / OSC_K, b = (v - rate / OSC_K) / w;
			u = (f0 + rate * h) / OSC_K + a * cos(w * h) + b * sin(w * h);
			v = rate / OSC_K - a * w * sin(w * h) + b * w * cos(w * h);
		}
		const double off = fabs(sm_simulation_positions(sim)[3] - (1.0 + u));
		const sm_statistics stats = sm_simulation_statistics(sim);
		printf("  %s: |x - exact| = %.3g m after %d calls, %lld steps, %lld restarts\n",
		       held ? "held" : "ramped", off, calls, (long long)stats.steps, (long long)stats.restarts);
		ENSURE(stats.restarts == 0 && off < (held ? 2e-5 : 5e-7));
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// A ramp runs from the time it is set (sm_simulation_set_external_force_ramp: force + rate (t -
// t_set)), not from t = 0: the oscillator of test_ramped_force_pushes_oscillator_as_closed_form,
// at rest until t_set = 1 s and pushed by f0 + r (t - t_set) from there, follows that test's
// closed form in s = t - t_set, with its tolerances (a ramp counted from t = 0 would push r t_set
// = 2 N harder, 0.05 m more of displacement).
static int test_ramp_set_later_runs_from_its_own_time(void)
{
	const double f0 = 0.5, r = 2.0, w = sqrt(OSC_K / OSC_M), t_set = 1.0;
	sm_model* model = oscillator(OSC_M, OSC_K, 0.0, 0.0);
	ENSURE(model != NULL);
	const sm_linear_solver solvers[] = {SM_SOLVER_DENSE, SM_SOLVER_REDUCED_PCG};
	for (size_t k = 0; k < sizeof solvers / sizeof solvers[0]; k++) {
		const sm_simulation_def d = tight_def(solvers[k]);
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_advance(sim, t_set), SM_OK);
		const double force[3] = {f0, 0.0, 0.0}, rate[3] = {r, 0.0, 0.0};
		ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, force, rate), SM_OK);
		double worst_x = 0.0, worst_f = 0.0, f[6];
		for (int i = 1; i <= 20; i++) {
			const double s = 0.1 * i;
			ENSURE_STATUS(sm_simulation_advance(sim, t_set + s), SM_OK);
			const double push = f0 + r * s;
			const double u = push / OSC_K - f0 / OSC_K * cos(w * s) - r / (OSC_K * w) * sin(w * s);
			worst_x = worst_of(worst_x, fabs(sm_simulation_positions(sim)[3] - (1.0 + u)));
			sm_simulation_forces(sim, f);
			worst_f = worst_of(worst_f, fabs(f[3] - (push - OSC_K * u)));
		}
		ENSURE(worst_x <= 1e-7);
		ENSURE(worst_f <= 4e-6);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// A caller that sets the ramp again before every advance, as an FMU master sets an input and its
// derivative at every communication point, with the force computed its own way (f0 + r t, or a
// sum of r h over the steps), continues it: no input change, so with restart_on_input_change
// CVODE takes the steps of the ramp set once. A force off the ramp by 1e-3 N restarts it (over the
// 0.01 s to the next call it changes the 1 kg bob's velocity by 1e-5 m/s, beyond the tolerance of
// 1e-6 m/s + rtol |v|); one off by 1e-9 N (1e-11 m/s) keeps the history, as a new rate from the
// force reached does.
static int test_ramp_continued_by_the_caller_is_no_change(void)
{
	sm_model* model = oscillator(OSC_M, OSC_K, 0.5, 0.1);
	ENSURE(model != NULL);
	sm_simulation_def def = sm_default_simulation_def();
	def.restart_on_input_change = true;
	const double f0[3] = {0.3, -0.2, 0.1}, r[3] = {1.5, 0.25, -0.75};
	const double h = 0.01;
	int64_t steps[6];
	double bob_x[6];
	for (int way = 0; way < 6; way++) {
		sm_simulation* sim = sm_simulation_create(model, &def, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, f0, r), SM_OK);
		double t = 0.0, summed[3] = {f0[0], f0[1], f0[2]};
		for (int k = 0; k < 100; k++) {
			if (way > 0 && k > 0) {
				double f[3], rate[3] = {r[0], r[1], r[2]};
				for (int c = 0; c < 3; c++)
					f[c] = way == 1 ? f0[c] + r[c] * t : way == 2 ? summed[c] : f0[c] + r[c] * t;
				if (k == 50 && (way == 3 || way == 5))
					f[0] += way == 3 ? 1e-3 : 1e-9;
				if (k == 50 && way == 4)
					rate[0] *= 2.0;
				ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, f, rate), SM_OK);
			}
			for (int c = 0; c < 3; c++)
				summed[c] += r[c] * h;
			t += h;
			ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
		}
		const sm_statistics stats = sm_simulation_statistics(sim);
		steps[way] = stats.steps;
		bob_x[way] = sm_simulation_positions(sim)[3];
		// One restart for the ramp set at t = 0; off the ramp by 1e-3 N at k = 50 one more and then,
		// back on the first ramp, one more again; off by 1e-9 N none. A new rate at k = 50 from the
		// force reached turns the ramp and keeps the history; the caller then gives the first ramp's
		// values, off the new one by 0.015 N: a jump, one restart, and on that ramp from there.
		ENSURE(stats.restarts == (way == 3 ? 3 : way == 4 ? 2 : 1));
		sm_simulation_destroy(sim);
	}
	// The same steps for the ramp set once and continued both ways; forces set differ from the ramp
	// by round-off only, so the bob's position does too (its scale 1 m: 1e-12).
	ENSURE(steps[1] == steps[0] && steps[2] == steps[0]);
	ENSURE_NEAR(bob_x[1], bob_x[0], 1e-12);
	ENSURE_NEAR(bob_x[2], bob_x[0], 1e-12);
	ENSURE(fabs(bob_x[3] - bob_x[0]) > 0.0 || steps[3] != steps[0]);
	ENSURE(fabs(bob_x[5] - bob_x[0]) > 0.0 || steps[5] != steps[0]);
	sm_model_destroy(model);
	return 0;
}

// A caller that continues an accelerating path computes x0 + v0 t + a t^2 / 2, which parts from
// the path's own x0 + t (v0 + t a / 2) by round-off of v0 t and a t^2 / 2. Where those cancel (a
// particle thrown out and pulled back, near its start again: v0 t = 0.24 m, the position 8.5e-5 m)
// the difference is 2e-18 m, many units of round-off of the position but few of the terms: no
// input change: the run is that of no second call, to the bit. The velocity likewise. (The path
// set at t = 0 gives the anchor a velocity, which the undamped spring does not feel at once, but
// the power its driver delivers against the stretched spring jumps: one restart, for it.)
static int test_accelerating_path_continued_near_its_start_is_no_change(void)
{
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.0, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	sm_simulation_def d = sm_default_simulation_def();
	d.restart_on_input_change = true;
	const double v0 = 0.3319437356282555, a = -0.9099679062492979, t = 0.7293151553060583;
	const double zero[3] = {0.0, 0.0, 0.0}, velocity[3] = {v0, 0.0, 0.0}, acceleration[3] = {a, 0.0, 0.0};
	const double x[3] = {v0 * t + 0.5 * a * t * t, 0.0, 0.0}, v[3] = {v0 + a * t, 0.0, 0.0};
	ENSURE(fabs(x[0] - t * (v0 + 0.5 * t * a)) > 16.0 * DBL_EPSILON * fabs(x[0]));
	double bob[2][3];
	for (int continued = 0; continued < 2; continued++) {
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 0, zero, velocity, acceleration), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
		if (continued)
			ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 0, x, v, acceleration), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(sim, t + 0.1), SM_OK);
		memcpy(bob[continued], sm_simulation_positions(sim) + 3, sizeof bob[continued]);
		ENSURE(sm_simulation_statistics(sim).restarts == 1);
		sm_simulation_destroy(sim);
	}
	ENSURE(memcmp(bob[0], bob[1], sizeof bob[0]) == 0);
	sm_model_destroy(model);
	return 0;
}

// A simulation of the model under the default options, restart_on_input_change set, or at
// rtol 1e-12 and absolute tolerances 1e-14 (m, m/s, J), the reference of the tests below.
static sm_simulation* restarting_simulation(const sm_model* model, bool tight)
{
	sm_simulation_def d = sm_default_simulation_def();
	d.restart_on_input_change = true;
	if (tight) {
		d.relative_tolerance = 1e-12;
		d.absolute_tolerance_position = d.absolute_tolerance_velocity = 1e-14;
	}
	return sm_simulation_create(model, &d, NULL);
}

// A drive set off its path restarts CVODE as a force's jump does, by the jump of its springs'
// forces on the free particles around it: the damped oscillator's anchor moving at 0.3 m/s, called
// every 0.01 s, set off its path once at 0.2 s and continued on the new path after. Off by 1e-3 m
// in position (40 N/m: 0.04 N on the 1 kg bob, 4e-4 m/s over the interval) or by 1e-3 m/s in
// velocity (0.5 N s/m: 5e-4 N, 5e-6 m/s) it restarts, beyond the velocity's tolerance of
// 1e-6 m/s + rtol |v|; off by 1e-9 of either (at most 4e-10 m/s) it keeps the history. Against
// the same inputs at rtol 1e-12 the bob is then 9.8e-7 m off at 0.5 s, as without the jump
// (measured; 3e-6 m asserted), where a restart at the jump costs 5.7e-6 m. The first call sets
// the anchor moving from rest (0.15 N on the bob through the damper): one restart.
static int test_a_drive_off_its_path_restarts_by_the_jump_of_its_springs_forces(void)
{
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.5, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const double off[4][2] = {{1e-3, 0.0}, {0.0, 1e-3}, {1e-9, 0.0}, {0.0, 1e-9}};
	for (int way = 0; way < 4; way++) {
		double bob[2];
		int64_t restarts = 0;
		for (int tight = 0; tight < 2; tight++) {
			sm_simulation* sim = restarting_simulation(model, tight);
			ENSURE(sim != NULL);
			const double h = 0.01, v0 = 0.3;
			for (int k = 0; k < 50; k++) {
				const double t = k * h, jump = k >= 20 ? 1.0 : 0.0;
				const double position[3] = {v0 * t + jump * (off[way][0] + off[way][1] * (t - 0.2)), 0.0,
				                            0.0};
				const double velocity[3] = {v0 + jump * off[way][1], 0.0, 0.0};
				ENSURE_STATUS(sm_simulation_set_driven(sim, 0, position, velocity), SM_OK);
				ENSURE_STATUS(sm_simulation_advance(sim, t + h), SM_OK);
			}
			bob[tight] = sm_simulation_positions(sim)[3];
			if (!tight)
				restarts = sm_simulation_statistics(sim).restarts;
			sm_simulation_destroy(sim);
		}
		printf("  off by %g m, %g m/s: %lld restarts, |x - tight| = %.3g m\n", off[way][0], off[way][1],
		       (long long)restarts, fabs(bob[0] - bob[1]));
		ENSURE(restarts == (way < 2 ? 2 : 1));
		if (way >= 2)
			ENSURE(fabs(bob[0] - bob[1]) <= 3e-6);
	}
	sm_model_destroy(model);
	return 0;
}

// Sets a test's inputs of the given size before the call at (0-based) index `call`.
typedef sm_status (*call_inputs)(sm_simulation* sim, int call, double size);

// Advances the model over 100 calls 0.01 s apart, `inputs` set before each, under the default
// options and at rtol 1e-12 (restarting_simulation): the inputs' work [J] of each at 1 s, and the
// restarts of the first.
static int work_over_calls(const sm_model* model, call_inputs inputs, double size, double work[2],
                           int64_t* restarts)
{
	for (int tight = 0; tight < 2; tight++) {
		sm_simulation* sim = restarting_simulation(model, tight);
		ENSURE(sim != NULL);
		for (int k = 0; k < 100; k++) {
			ENSURE_STATUS(inputs(sim, k, size), SM_OK);
			ENSURE_STATUS(sm_simulation_advance(sim, (k + 1) * 0.01), SM_OK);
		}
		work[tight] = sm_simulation_input_work(sim);
		if (!tight)
			*restarts = sm_simulation_statistics(sim).restarts;
		sm_simulation_destroy(sim);
	}
	return 0;
}

// The anchor (particle 0) held at rest until 0.2 s, moving at `speed` [m/s] from there.
static sm_status anchor_set_moving(sm_simulation* sim, int call, double speed)
{
	if (call < 20)
		return SM_OK;
	const double position[3] = {speed * (call * 0.01 - 0.2), 0.0, 0.0}, velocity[3] = {speed, 0.0, 0.0};
	return sm_simulation_set_driven(sim, 0, position, velocity);
}

// The drives set moving at speeds[0] [m/s] restart CVODE once (at the start of their motion) and
// leave the inputs' work within 3e-6 J of the tight run's (work_over_calls); at speeds[1] they
// restart nothing and stay as close. `unit` labels the speed in the printed line.
static int drive_speeds_restart_once_then_never(const sm_model* model, call_inputs inputs,
                                                const double speeds[2], const char* unit)
{
	for (int way = 0; way < 2; way++) {
		double work[2];
		int64_t restarts = 0;
		ENSURE(work_over_calls(model, inputs, speeds[way], work, &restarts) == 0);
		printf("  %g %s: %lld restarts, work %.6g J, |W - tight| = %.3g J\n", speeds[way], unit,
		       (long long)restarts, work[0], fabs(work[0] - work[1]));
		ENSURE(restarts == (way == 0 ? 1 : 0));
		ENSURE(fabs(work[0] - work[1]) <= 3e-6);
	}
	return 0;
}

// A drive's velocity jump at an undamped spring moves no force at once, but the power its driver
// delivers jumps by the spring's force times it, and the inputs' work integrated with the state
// errs by that jump times the steps that follow unless CVODE restarts. The anchor of an undamped
// oscillator stretched by 0.1 m (100 N/m: 10 N), held at rest and called every 0.01 s, set moving
// at 1e-3 m/s at 0.2 s (position continuous), does 1.45e-3 J of work by 1 s. With CVODE's
// history kept over the jump that work was 2.2e-5 J off a run at rtol 1e-12 (the work's
// tolerance is 1e-6 J); restarted, 5.8e-7 J (measured; 3e-6 J asserted). At 1e-9 m/s the
// power's jump, 1e-8 W over the 0.01 s interval, is far within the tolerance: no restart.
static int test_a_drive_velocity_jump_restarts_by_the_jump_of_its_drivers_power(void)
{
	sm_model* model = oscillator_anchored(OSC_M, 100.0, 0.0, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const double speeds[2] = {1e-3, 1e-9};
	ENSURE(drive_speeds_restart_once_then_never(model, anchor_set_moving, speeds, "m/s") == 0);
	sm_model_destroy(model);
	return 0;
}

// 200 undamped oscillators side by side along y, 2 m apart, each as in the test above: a driven
// anchor and a 1 kg bob on a spring of 100 N/m and rest length 1 m, stretched by 0.1 m.
enum { OSCILLATORS = 200 };
static sm_model* driven_oscillators(void)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&md, NULL);
	if (model == NULL)
		return NULL;
	for (int32_t i = 0; i < OSCILLATORS; i++) {
		sm_particle_def anchor = sm_default_particle_def(), bob = sm_default_particle_def();
		anchor.motion = SM_PARTICLE_DRIVEN;
		anchor.position[1] = bob.position[1] = 2.0 * i;
		bob.position[0] = 1.1;
		sm_spring_def s = sm_default_spring_def();
		s.a = 2 * i;
		s.b = 2 * i + 1;
		s.rest_length = 1.0;
		s.stiffness = 100.0;
		if (sm_model_add_particle(model, &anchor, NULL) != SM_OK ||
		    sm_model_add_particle(model, &bob, NULL) != SM_OK ||
		    sm_model_add_spring(model, &s, NULL) != SM_OK) {
			sm_model_destroy(model);
			return NULL;
		}
	}
	return model;
}

// Every anchor of driven_oscillators held at rest until 0.2 s, moving at `speed` [m/s] along x
// from there.
static sm_status anchors_set_moving(sm_simulation* sim, int call, double speed)
{
	for (int32_t i = 0; i < OSCILLATORS && call >= 20; i++) {
		const double position[3] = {speed * (call * 0.01 - 0.2), 2.0 * i, 0.0};
		const double velocity[3] = {speed, 0.0, 0.0};
		const sm_status st = sm_simulation_set_driven(sim, 2 * i, position, velocity);
		if (st != SM_OK)
			return st;
	}
	return SM_OK;
}

// The inputs' work is one sum: the power's jumps of the drives that jump before an advance add up
// in its rate, and CVODE restarts when their sum, not each alone, is beyond what the history
// carries. The 200 anchors of driven_oscillators set moving at 5e-6 m/s at 0.2 s, each against
// its spring's 4.2 N then: each driver's power jumps by 2.1e-5 W, 2.1e-7 J over the 0.01 s
// interval, within the work's tolerance of 1e-6 J; together by 4.2e-3 W, 4.2e-5 J. Against a run
// at rtol 1e-12, the work of 1.45e-3 J was 1.3e-5 J off with the history kept; restarted,
// 1.3e-6 J (measured; 3e-6 J asserted, as for the one anchor above). At 5e-12 m/s each,
// 4.2e-11 J together, nothing restarts.
static int test_small_drive_jumps_together_restart_by_the_sum_of_their_power(void)
{
	sm_model* model = driven_oscillators();
	ENSURE(model != NULL);
	const double speeds[2] = {5e-6, 5e-12};
	ENSURE(drive_speeds_restart_once_then_never(model, anchors_set_moving, speeds, "m/s each") == 0);
	sm_model_destroy(model);
	return 0;
}

// An undamped oscillator along x, a fixed anchor at the origin and a 1 kg bob on a spring of
// 100 N/m and rest length 20 m, released 10 m from it: u = 10 cos(10 t) m, the bob at up to
// 100 m/s, its spring never shorter than 10 m.
static sm_model* fast_oscillator(void)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&md, NULL);
	sm_particle_def anchor = sm_default_particle_def(), bob = sm_default_particle_def();
	anchor.motion = SM_PARTICLE_FIXED;
	bob.position[0] = 30.0;
	sm_spring_def s = sm_default_spring_def();
	s.a = 0;
	s.b = 1;
	s.rest_length = 20.0;
	s.stiffness = 100.0;
	if (!model || sm_model_add_particle(model, &anchor, NULL) != SM_OK ||
	    sm_model_add_particle(model, &bob, NULL) != SM_OK || sm_model_add_spring(model, &s, NULL) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// A force that jumps is carried by the history when the advance's interval, or max_step if shorter,
// times |jump| / m is at most the velocity's tolerance (docs/simulation.md): 1e-4 N on the 1 kg bob
// of the oscillator at rest, whose velocity's tolerance is atol = 1e-6 m/s, is 100 1/s. Over an
// advance of 0.1 s (10 times the tolerance) it restarts CVODE, unless max_step = 1 ms caps the
// steps (0.1 of it). The bob moves as u = J / k (1 - cos w t), 4.8e-7 m at 0.6 s, its velocity
// about 16 times the velocity's tolerance: measured 4e-9 m off with the history kept, 1.6e-7 m
// after the restart's first-order start (the tolerance, 1e-6 m/s over 0.1 s, is 1e-7 m): 2e-8 m
// and 3e-7 m.
static int test_a_force_jump_within_max_step_keeps_the_history(void)
{
	const double jump = 1e-4, t0 = 0.5, t1 = 0.6, w = sqrt(OSC_K / OSC_M);
	sm_model* model = oscillator(OSC_M, OSC_K, 0.0, 0.0);
	ENSURE(model != NULL);
	for (int capped = 0; capped < 2; capped++) {
		sm_simulation_def d = sm_default_simulation_def();
		d.max_step = capped ? 1e-3 : 0.0;
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		ENSURE_STATUS(sm_simulation_advance(sim, t0), SM_OK);
		const double force[3] = {jump, 0.0, 0.0};
		ENSURE_STATUS(sm_simulation_set_external_force(sim, 1, force), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(sim, t1), SM_OK);
		const double u = jump / OSC_K * (1.0 - cos(w * (t1 - t0)));
		printf("  max_step %g s: %lld restarts, u %.6g m, off %.3g m\n", d.max_step,
		       (long long)sm_simulation_statistics(sim).restarts, sm_simulation_positions(sim)[3] - 1.0,
		       sm_simulation_positions(sim)[3] - 1.0 - u);
		ENSURE(sm_simulation_statistics(sim).restarts == (capped ? 0 : 1));
		ENSURE_NEAR(sm_simulation_positions(sim)[3], 1.0 + u, capped ? 2e-8 : 3e-7);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// A force sampled and held on a fast particle jumps at every call by little against the velocity's
// tolerance, and keeps the history, though the power it delivers jumps by the jump times a
// velocity of up to 100 m/s: a restart at each jump would cost the motion about rtol each time,
// while the work, integrated with the state, errs by as much either way. The bob of
// fast_oscillator under 0.01 N sin(2 pi t) held over each 1 ms for 2 s (jumps of up to 6.3e-5 N,
// 6.3e-8 m/s over a call against at least 1e-6 m/s; 6.3e-3 W): measured against the same samples
// at rtol 1e-12, the history kept, 0 restarts, the bob 4.2e-7 m and the work 3.1e-4 J off; with
// a restart wherever the power's jump times the call's interval exceeded the work's tolerance
// rtol |W| + 1e-6 J, 1436 restarts, 1.4e-2 m and 2.9e-4 J. Asserted: no restart, and the bob
// within 1e-5 m, rtol of its 10 m swing.
static int test_a_force_held_over_each_call_on_a_fast_particle_keeps_the_history(void)
{
	sm_model* model = fast_oscillator();
	ENSURE(model != NULL);
	double bob[2] = {0.0, 0.0};
	int64_t restarts = 0;
	for (int tight = 0; tight < 2; tight++) {
		sm_simulation* sim = restarting_simulation(model, tight);
		ENSURE(sim != NULL);
		const double h = 1e-3;
		for (int k = 0; k < 2000; k++) {
			const double force[3] = {0.01 * sin(2.0 * acos(-1.0) * k * h), 0.0, 0.0};
			ENSURE_STATUS(sm_simulation_set_external_force(sim, 1, force), SM_OK);
			ENSURE_STATUS(sm_simulation_advance(sim, (k + 1) * h), SM_OK);
		}
		bob[tight] = sm_simulation_positions(sim)[3];
		if (!tight)
			restarts = sm_simulation_statistics(sim).restarts;
		sm_simulation_destroy(sim);
	}
	printf("  %lld restarts, |x - tight| = %.3g m\n", (long long)restarts, fabs(bob[0] - bob[1]));
	ENSURE(restarts == 0);
	ENSURE(fabs(bob[0] - bob[1]) <= 1e-5);
	sm_model_destroy(model);
	return 0;
}

// The oscillator's anchor driven from rest with a constant acceleration a along the spring: in the
// anchor's frame the stretch u = x_bob - x_anchor - l0 obeys m u'' + k u = -m a from u = u' = 0,
// so u = -a / w^2 (1 - cos(w t)). The anchor itself is at a t^2 / 2 with velocity a t, each one
// multiply-add of numbers of order 1 (1e-15); the bob's error as in the ramp test (1e-7 m).
static int test_accelerating_anchor_drags_bob_as_closed_form(void)
{
	const double a = 0.6, w = sqrt(OSC_K / OSC_M);
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.0, 0.0, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	const double zero[3] = {0.0, 0.0, 0.0}, acceleration[3] = {a, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 0, zero, zero, acceleration), SM_OK);
	double worst_bob = 0.0, worst_anchor = 0.0;
	for (int i = 1; i <= 20; i++) {
		const double t = 0.1 * i;
		ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
		const double* x = sm_simulation_positions(sim);
		const double* v = sm_simulation_velocities(sim);
		const double anchor = 0.5 * a * t * t, u = -a / (w * w) * (1.0 - cos(w * t));
		worst_anchor = worst_of(worst_anchor, fmax(fabs(x[0] - anchor), fabs(v[0] - a * t)));
		worst_bob = worst_of(worst_bob, fabs(x[3] - (anchor + 1.0 + u)));
	}
	printf("  max |anchor - path| = %.3g, max |bob - closed form| = %.3g m\n", worst_anchor, worst_bob);
	ENSURE(worst_anchor <= 1e-15);
	ENSURE(worst_bob <= 1e-7);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// pulled_spring()'s driven particle pulled from rest with acceleration a: spring 0 reaches its
// 10 % break strain when a t^2 / 2 = 0.1 m, at t = sqrt(0.2 / a). CVODE locates the root to 100
// units of round-off of the time, as for the constant speed (test_simulation.c): 1e-12 s. The
// break is found inside a step, on the driven particle's quadratic path.
static int test_spring_pulled_with_constant_acceleration_breaks_at_analytic_time(void)
{
	sm_model* model = pulled_spring();
	ENSURE(model != NULL);
	sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
	ENSURE(sim != NULL);
	const double a = 0.5, x1[3] = {1.0, 0.0, 0.0}, v1[3] = {0.0, 0.0, 0.0}, a1[3] = {a, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 1, x1, v1, a1), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 2.0), SM_OK);
	ENSURE(sm_simulation_break_count(sim) == 1);
	const sm_break_event e = sm_simulation_break(sim, 0);
	ENSURE(e.spring == 0);
	printf("  break at %.17g s, |error| %.3g s\n", e.time, fabs(e.time - sqrt(0.2 / a)));
	ENSURE_NEAR(e.time, sqrt(0.2 / a), 1e-12);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// A driven particle thrown outward at v0 and pulled back by a constant deceleration a stretches
// pulled_spring()'s spring 0 by at most v0^2 / (2 a), here 0.1 m (1 + delta), so the strain passes
// its 10 % limit only for 2 sqrt(0.2 delta / a) = 0.4 ms around t = v0 / a: inside one step, whose
// ends both see the spring below its limit. The search of each step finds the excursion on the
// particle's quadratic path (a straight one misses it), and the break comes at the first crossing,
// l0 + v0 t - a t^2 / 2 = 1.1 m: t = (v0 - sqrt(v0^2 - 0.2 a)) / a, located by CVODE to 1e-10 s
// (the root's slope, a times 0.2 ms, is 1e-3 m/s).
static int test_decelerating_pull_breaks_the_spring_inside_a_step(void)
{
	const double v0 = 1.0, delta = 1e-6, a = v0 * v0 / (0.2 * (1.0 + delta));
	sm_model* model = pulled_spring();
	ENSURE(model != NULL);
	sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
	ENSURE(sim != NULL);
	const double x1[3] = {1.0, 0.0, 0.0}, v1[3] = {v0, 0.0, 0.0}, a1[3] = {-a, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 1, x1, v1, a1), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 0.5), SM_OK);
	ENSURE(sm_simulation_break_count(sim) == 1);
	const double t_break = (v0 - sqrt(v0 * v0 - 0.2 * a)) / a;
	printf("  break at %.17g s, |error| %.3g s\n", sm_simulation_break(sim, 0).time,
	       fabs(sm_simulation_break(sim, 0).time - t_break));
	ENSURE_NEAR(sm_simulation_break(sim, 0).time, t_break, 1e-10);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// pulled_spring() without gravity: its free particle hangs at rest, so CVODE's steps grow long at
// order 1. A driven particle thrown outward at v0 = 1 m/s and pulled back at a stretches spring 0 by
// v0^2 / (2 a) at most: 0.07 m, below its 0.1 m limit, at a = 7.14 m/s^2 (no break), and by
// 0.1 m (1 + 1e-6) (a break at the first crossing, as in the test above). The search of a
// first-order step took the driven path as its tangent, which overshoots a decelerating path: the
// spring broke at t = 0.1 s, at a strain of 0.064, in both runs.
static int test_decelerating_pull_in_long_first_order_steps_breaks_only_past_the_limit(void)
{
	sm_model* model = pulled_spring();
	ENSURE(model != NULL);
	sm_model_def md = sm_model_get_def(model);
	md.gravity[2] = 0.0;
	ENSURE_STATUS(sm_model_set_def(model, &md), SM_OK);
	const double stretches[2] = {0.07, 0.1 * (1.0 + 1e-6)};
	for (int k = 0; k < 2; k++) {
		const double v0 = 1.0, a = v0 * v0 / (2.0 * stretches[k]);
		sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
		ENSURE(sim != NULL);
		const double x1[3] = {1.0, 0.0, 0.0}, v1[3] = {v0, 0.0, 0.0}, a1[3] = {-a, 0.0, 0.0};
		ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 1, x1, v1, a1), SM_OK);
		ENSURE_STATUS(sm_simulation_advance(sim, 0.4), SM_OK);
		printf("  largest stretch %.3g m: %d breaks", stretches[k], (int)sm_simulation_break_count(sim));
		if (sm_simulation_break_count(sim) > 0)
			printf(", at %.17g s", sm_simulation_break(sim, 0).time);
		printf("\n");
		ENSURE(sm_simulation_break_count(sim) == k);
		if (k == 1)
			ENSURE_NEAR(sm_simulation_break(sim, 0).time, (v0 - sqrt(v0 * v0 - 0.2 * a)) / a, 1e-10);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// The same decelerating pull with nothing free to move (pulled_spring()'s hanging particle held)
// and loose tolerances (rtol = atol = 0.1), so that CVODE's steps are long at order 1: the largest
// stretch, v0^2 / (2 a) = 0.09 m, stays below the 0.1 m limit, and nothing may break. A search
// that followed the driven particle on the tangent of its path at the step's start (CVODE's
// order 1), not on the parabola itself, broke the spring here: the tangent overshoots a
// decelerating path by a H^2 / 2, the 1 cm left to the limit over a step of 0.06 s.
static int test_decelerating_pull_in_loose_first_order_steps_breaks_nothing(void)
{
	sm_model* model = pulled_spring();
	ENSURE(model != NULL);
	sm_model_def md = sm_model_get_def(model);
	md.gravity[2] = 0.0;
	ENSURE_STATUS(sm_model_set_def(model, &md), SM_OK);
	sm_particle_def held;
	ENSURE_STATUS(sm_model_get_particle(model, 2, &held), SM_OK);
	held.motion = SM_PARTICLE_FIXED;
	ENSURE_STATUS(sm_model_set_particle(model, 2, &held), SM_OK);
	sm_simulation_def d = sm_default_simulation_def();
	d.relative_tolerance = d.absolute_tolerance_position = d.absolute_tolerance_velocity = 0.1;
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	const double v0 = 1.0, a = v0 * v0 / (2.0 * 0.09);
	const double x1[3] = {1.0, 0.0, 0.0}, v1[3] = {v0, 0.0, 0.0}, a1[3] = {-a, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 1, x1, v1, a1), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 0.6), SM_OK);
	printf("  %lld steps, %d breaks\n", (long long)sm_simulation_statistics(sim).steps,
	       (int)sm_simulation_break_count(sim));
	ENSURE(sm_simulation_break_count(sim) == 0);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// Ramps and accelerations belong to the state: a snapshot taken mid-ramp, restored into the same
// simulation or read back from bytes into a new one, goes on along them (the same bits both ways,
// and within the tolerances of the run that went on without a restart: at rtol 1e-10 each run is
// within about 1e-9 m of the exact motion, as in the closed-form tests, so 1e-7 m); a reset clears
// them (the same bits as a new simulation given no inputs).
static int test_ramps_are_part_of_the_state(void)
{
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.5, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	sm_simulation* other = sm_simulation_create(model, &d, NULL);
	sm_simulation* plain = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL && other != NULL && plain != NULL);
	const double zero[3] = {0.0, 0.0, 0.0}, v[3] = {0.1, 0.0, 0.0}, a[3] = {0.4, -0.3, 0.0};
	const double f0[3] = {0.2, 0.0, 0.1}, r[3] = {-0.5, 1.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 0, zero, v, a), SM_OK);
	ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, f0, r), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 0.3), SM_OK);
	sm_simulation_state* saved = sm_simulation_save_state(sim);
	ENSURE(saved != NULL);
	const size_t size = sm_simulation_state_size(saved);
	unsigned char* bytes = malloc(size);
	ENSURE(bytes != NULL);
	ENSURE_STATUS(sm_simulation_state_serialize(saved, bytes, size), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 1.0), SM_OK);
	double through[6], restored[6];
	memcpy(through, sm_simulation_positions(sim), sizeof through);
	ENSURE_STATUS(sm_simulation_restore_state(sim, saved), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 1.0), SM_OK);
	memcpy(restored, sm_simulation_positions(sim), sizeof restored);
	sm_simulation_state* read = sm_simulation_state_deserialize(bytes, size, NULL);
	ENSURE(read != NULL);
	ENSURE_STATUS(sm_simulation_restore_state(other, read), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(other, 1.0), SM_OK);
	ENSURE(memcmp(sm_simulation_positions(other), restored, sizeof restored) == 0);
	for (int k = 0; k < 6; k++)
		ENSURE_NEAR(restored[k], through[k], 1e-7);
	// The anchor's path is exact: x0 + v t + a t^2 / 2 at t = 1 s.
	ENSURE_NEAR(restored[0], 0.1 + 0.2, 1e-15);
	ENSURE_NEAR(restored[1], -0.15, 1e-15);
	ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(sim, 1.0), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(plain, 1.0), SM_OK);
	ENSURE(memcmp(sm_simulation_positions(sim), sm_simulation_positions(plain), sizeof restored) == 0);
	free(bytes);
	sm_simulation_state_destroy(saved);
	sm_simulation_state_destroy(read);
	sm_simulation_destroy(sim);
	sm_simulation_destroy(other);
	sm_simulation_destroy(plain);
	sm_model_destroy(model);
	return 0;
}

// As for a driven motion (test_simulation.c, test_restore_and_set_state_refuse_a_driven_motion_that_
// overflows): a ramp and a time at which its force is not finite, 1e10 N/s set at t = 0 and a
// snapshot's time made 1e300 s, or set_state to that time, are refused with nothing changed. They
// were taken: the forces read back infinite and the next advance failed at its first right-hand
// side. At 1 s the force, 1e10 N, is finite and both are taken.
static int test_restore_and_set_state_refuse_a_ramp_that_overflows(void)
{
	sm_model* model = oscillator(OSC_M, OSC_K, 0.0, 0.1);
	ENSURE(model != NULL);
	sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
	sm_simulation* other = sm_simulation_create(model, NULL, NULL);
	ENSURE(sim != NULL && other != NULL);
	const double zero[3] = {0.0, 0.0, 0.0}, steep[3] = {1e10, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, zero, steep), SM_OK);
	sm_simulation_state* saved = sm_simulation_save_state(sim);
	ENSURE(saved != NULL);
	ENSURE_STATUS(sm_simulation_advance(other, 0.01), SM_OK);
	double x[6], f[6];
	memcpy(x, sm_simulation_positions(other), sizeof x);
	const double times[2] = {1e300, 1.0};
	for (int k = 0; k < 2; k++) {
		sm_simulation_state* forged = state_at_time(saved, times[k]);
		ENSURE(forged != NULL);
		const sm_status st = sm_simulation_restore_state(other, forged);
		sm_simulation_state_destroy(forged);
		sm_simulation_forces(other, f);
		if (k == 0) {
			ENSURE_STATUS(st, SM_ERROR_NOT_FINITE);
			ENSURE(strstr(sm_simulation_last_error(other), "particle 1") != NULL);
			ENSURE(sm_simulation_time(other) == 0.01 &&
			       memcmp(sm_simulation_positions(other), x, sizeof x) == 0);
			ENSURE(isfinite(f[3]));
		} else {
			ENSURE_STATUS(st, SM_OK);
			ENSURE(sm_simulation_time(other) == 1.0);
			ENSURE_NEAR(f[3], 1e10 - OSC_K * 0.1, 1e-3);  // the ramp, less the stretched spring
		}
	}
	double v[6] = {0};
	memcpy(x, sm_simulation_positions(sim), sizeof x);
	ENSURE_STATUS(sm_simulation_set_state(sim, 1e300, x, v), SM_ERROR_NOT_FINITE);
	ENSURE(strstr(sm_simulation_last_error(sim), "particle 1") != NULL);
	ENSURE(sm_simulation_time(sim) == 0.0);
	ENSURE_STATUS(sm_simulation_set_state(sim, 1.0, x, v), SM_OK);
	sm_simulation_state_destroy(saved);
	sm_simulation_destroy(other);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

// The same for the first particle, whose index 0 the checks report as the one that overflows: the
// driven anchor of an oscillator set moving at 1e10 m/s, or given a ramp of 1e10 N/s (a held
// particle's force moves nothing, but it reads infinite in its reaction), both at t = 0. The
// snapshot's time made 1e300 s and set_state to that time are refused, naming particle 0, with
// nothing changed.
static int test_restore_and_set_state_refuse_the_first_particles_overflowing_input(void)
{
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.0, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	const double zero[3] = {0.0, 0.0, 0.0}, steep[3] = {1e10, 0.0, 0.0}, huge_time = 1e300;
	for (int ramp = 0; ramp < 2; ramp++) {
		sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
		sm_simulation* other = sm_simulation_create(model, NULL, NULL);
		ENSURE(sim != NULL && other != NULL);
		ENSURE_STATUS(ramp ? sm_simulation_set_external_force_ramp(sim, 0, zero, steep)
		                   : sm_simulation_set_driven(sim, 0, zero, steep),
		              SM_OK);
		sm_simulation_state* saved = sm_simulation_save_state(sim);
		ENSURE(saved != NULL);
		sm_simulation_state* forged = state_at_time(saved, huge_time);
		ENSURE(forged != NULL);
		ENSURE_STATUS(sm_simulation_advance(other, 0.01), SM_OK);
		double x[6], v[6] = {0};
		memcpy(x, sm_simulation_positions(other), sizeof x);
		ENSURE_STATUS(sm_simulation_restore_state(other, forged), SM_ERROR_NOT_FINITE);
		ENSURE(strstr(sm_simulation_last_error(other), "particle 0") != NULL);
		ENSURE(sm_simulation_time(other) == 0.01 && memcmp(sm_simulation_positions(other), x, sizeof x) == 0);
		memcpy(x, sm_simulation_positions(sim), sizeof x);
		ENSURE_STATUS(sm_simulation_set_state(sim, huge_time, x, v), SM_ERROR_NOT_FINITE);
		ENSURE(strstr(sm_simulation_last_error(sim), "particle 0") != NULL);
		ENSURE(sm_simulation_time(sim) == 0.0);
		sm_simulation_state_destroy(forged);
		sm_simulation_state_destroy(saved);
		sm_simulation_destroy(other);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// Bad arguments change nothing: non-finite rates and accelerations are refused with a message
// naming the particle, and a ramp on a held particle moves nothing.
static int test_bad_ramps_are_refused(void)
{
	sm_model* model = oscillator_anchored(OSC_M, OSC_K, 0.0, 0.1, SM_PARTICLE_DRIVEN);
	ENSURE(model != NULL);
	sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
	ENSURE(sim != NULL);
	const double zero[3] = {0.0, 0.0, 0.0}, bad[3] = {0.0, NAN, 0.0}, one[3] = {1.0, 0.0, 0.0};
	ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 1, zero, bad), SM_ERROR_NOT_FINITE);
	ENSURE(strstr(sm_simulation_last_error(sim), "particle 1") != NULL);
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 0, zero, zero, bad), SM_ERROR_NOT_FINITE);
	ENSURE_STATUS(sm_simulation_set_driven_accelerating(sim, 1, zero, zero, one), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(strstr(sm_simulation_last_error(sim), "not driven") != NULL);
	// The driven anchor's ramp moves nothing: the bob oscillates as without it.
	ENSURE_STATUS(sm_simulation_set_external_force_ramp(sim, 0, one, one), SM_OK);
	sm_simulation* plain = sm_simulation_create(model, NULL, NULL);
	ENSURE(plain != NULL);
	ENSURE_STATUS(sm_simulation_advance(sim, 1.0), SM_OK);
	ENSURE_STATUS(sm_simulation_advance(plain, 1.0), SM_OK);
	ENSURE(memcmp(sm_simulation_positions(sim), sm_simulation_positions(plain), 6 * sizeof(double)) == 0);
	ENSURE(sm_simulation_statistics(sim).steps == sm_simulation_statistics(plain).steps);
	sm_simulation_destroy(plain);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_ramped_force_pushes_oscillator_as_closed_form);
	RUN_TEST(test_ramp_set_later_runs_from_its_own_time);
	RUN_TEST(test_ramp_continued_by_the_caller_is_no_change);
	RUN_TEST(test_a_force_that_turns_at_every_call_keeps_the_history);
	RUN_TEST(test_a_drive_off_its_path_restarts_by_the_jump_of_its_springs_forces);
	RUN_TEST(test_a_drive_velocity_jump_restarts_by_the_jump_of_its_drivers_power);
	RUN_TEST(test_small_drive_jumps_together_restart_by_the_sum_of_their_power);
	RUN_TEST(test_a_force_held_over_each_call_on_a_fast_particle_keeps_the_history);
	RUN_TEST(test_a_force_jump_within_max_step_keeps_the_history);
	RUN_TEST(test_accelerating_anchor_drags_bob_as_closed_form);
	RUN_TEST(test_accelerating_path_continued_near_its_start_is_no_change);
	RUN_TEST(test_spring_pulled_with_constant_acceleration_breaks_at_analytic_time);
	RUN_TEST(test_decelerating_pull_breaks_the_spring_inside_a_step);
	RUN_TEST(test_decelerating_pull_in_long_first_order_steps_breaks_only_past_the_limit);
	RUN_TEST(test_decelerating_pull_in_loose_first_order_steps_breaks_nothing);
	RUN_TEST(test_ramps_are_part_of_the_state);
	RUN_TEST(test_restore_and_set_state_refuse_a_ramp_that_overflows);
	RUN_TEST(test_restore_and_set_state_refuse_the_first_particles_overflowing_input);
	RUN_TEST(test_bad_ramps_are_refused);
	return TEST_SUMMARY();
}

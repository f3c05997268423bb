// Large motions of rest-length springs, where the law's nonlinearity (the direction u turning with
// the spring, the geometric stiffness ks (1 - l0/L)) carries the physics, each against a closed
// form or a conservation law, with every linear solver and with Adams.
#include "simulation_fixtures.h"
#include "springmass/model.h"
#include "springmass/simulation.h"
#include "test_harness.h"

#include <stdlib.h>

static const double pi = 3.14159265358979323846;

// The integrators the tests run: BDF with each linear solver, then Adams (no linear solver).
#define INTEGRATOR_COUNT (SM_SOLVER_COUNT - SM_SOLVER_DENSE + 1)

static sm_simulation_def integrator_def(int which)
{
	if (which == INTEGRATOR_COUNT - 1) {
		sm_simulation_def d = tight_def(SM_SOLVER_AUTO);
		d.method = SM_METHOD_ADAMS;
		return d;
	}
	return tight_def((sm_linear_solver)(SM_SOLVER_DENSE + which));
}

static const char* integrator_name(int which)
{
	return which == INTEGRATOR_COUNT - 1 ? "adams"
	                                     : sm_linear_solver_name((sm_linear_solver)(SM_SOLVER_DENSE + which));
}

// Orthonormal e1 = (1, 2, 2) / 3 and e2 = (2, 1, -2) / 3 with their components turned cyclically
// by `turn` places, e2 reversed for odd `turn` (the other sense of rotation): planes of motion
// oblique to every axis, so that every entry of the springs' 3 x 3 blocks takes part.
static void oblique_plane(int turn, double e1[3], double e2[3])
{
	const double a[3] = {1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0}, b[3] = {2.0 / 3.0, 1.0 / 3.0, -2.0 / 3.0};
	for (int c = 0; c < 3; c++) {
		e1[c] = a[(c + turn) % 3];
		e2[c] = (turn % 2 ? -1.0 : 1.0) * b[(c + turn) % 3];
	}
}

// ---------------------------------------------------------------------------------------------
// Steady whirling
// ---------------------------------------------------------------------------------------------

#define WHIRLERS 6

// Bob b of mass m_b [kg] on a spring of k_b [N/m] and rest length 1 m to its own fixed anchor c_b,
// no gravity, on a circle of radius r_b [m] in the plane oblique_plane(b): the spring's pull
// k (r - l0) is the centripetal force m w^2 r at w_b = sqrt(k (r - l0) / (m r)) [rad/s].
typedef struct whirler {
	double mass, stiffness, radius, omega, centre[3], e1[3], e2[3];
} whirler;

static whirler whirler_of(int b)
{
	whirler w;
	w.mass = 0.5 + 0.25 * b;
	w.stiffness = 60.0 + 20.0 * b;
	w.radius = 1.1 + 0.1 * b;  // stretched by 10 % to 60 %
	w.omega = sqrt(w.stiffness * (w.radius - 1.0) / (w.mass * w.radius));
	w.centre[0] = 0.3 * b;
	w.centre[1] = -0.5 + 0.2 * b;
	w.centre[2] = 0.1 * b;
	oblique_plane(b, w.e1, w.e2);
	return w;
}

// Particles 2 b (anchor) and 2 b + 1 (bob), spring b, for b < WHIRLERS: six springs, so that the
// four-wide, two-wide and scalar spring loops all carry whirling bobs.
static sm_model* whirling_bobs(void)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&md, NULL);
	for (int b = 0; model != NULL && b < WHIRLERS; b++) {
		const whirler w = whirler_of(b);
		sm_particle_def anchor = sm_default_particle_def();
		anchor.motion = SM_PARTICLE_FIXED;
		sm_particle_def bob = sm_default_particle_def();
		bob.mass = w.mass;
		for (int c = 0; c < 3; c++) {
			anchor.position[c] = w.centre[c];
			bob.position[c] = w.centre[c] + w.radius * w.e1[c];
			bob.velocity[c] = w.omega * w.radius * w.e2[c];
		}
		sm_spring_def s = sm_default_spring_def();
		s.a = 2 * b;
		s.b = 2 * b + 1;
		s.rest_length = 1.0;
		s.stiffness = w.stiffness;
		if (sm_model_add_particle(model, &anchor, NULL) != SM_OK ||
		    sm_model_add_particle(model, &bob, NULL) != SM_OK ||
		    sm_model_add_spring(model, &s, NULL) != SM_OK) {
			sm_model_destroy(model);
			return NULL;
		}
	}
	return model;
}

// A bob launched tangentially at the speed of steady circular motion stays on its circle at the
// angular speed the rest-length law gives: x_b(t) = c_b + r_b (cos(w_b t) e1 + sin(w_b t) e2).
// Checked over ten turns of the slowest bob (w from 3.3 to 5.9 rad/s), every 1/16 turn of it.
static int test_bobs_whirl_steadily_on_their_circles(void)
{
	sm_model* model = whirling_bobs();
	ENSURE(model != NULL);
	double slowest = INFINITY;
	for (int b = 0; b < WHIRLERS; b++)
		slowest = fmin(slowest, whirler_of(b).omega);
	const double duration = 10.0 * 2.0 * pi / slowest;
	for (int which = 0; which < INTEGRATOR_COUNT; which++) {
		const sm_simulation_def d = integrator_def(which);
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		ENSURE(sim != NULL);
		double worst_radius = 0.0, worst_position = 0.0;
		for (int i = 1; i <= 160; i++) {
			const double t = duration * i / 160.0;
			ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
			const double* x = sm_simulation_positions(sim);
			for (int b = 0; b < WHIRLERS; b++) {
				const whirler w = whirler_of(b);
				const double* xb = x + 3 * (2 * b + 1);
				double d2 = 0.0, e2 = 0.0;
				for (int c = 0; c < 3; c++) {
					const double exact =
					    w.centre[c] + w.radius * (cos(w.omega * t) * w.e1[c] + sin(w.omega * t) * w.e2[c]);
					d2 += (xb[c] - w.centre[c]) * (xb[c] - w.centre[c]);
					e2 += (xb[c] - exact) * (xb[c] - exact);
				}
				worst_radius = worst_of(worst_radius, fabs(sqrt(d2) - w.radius));
				worst_position = worst_of(worst_position, sqrt(e2));
			}
		}
		printf("  %-8s largest radius error %.3e m, position error %.3e m, %ld steps\n",
		       integrator_name(which), worst_radius, worst_position,
		       (long)sm_simulation_statistics(sim).steps);
		// About 5500 BDF steps (3000 Adams), each allowed 1e-10 of a state of positions up to 2 m and
		// speeds up to 9.4 m/s, add up to about 1e-5 m of phase along the circles (measured 8e-6 m
		// with BDF, 3e-7 m with Adams); the radius, held by the spring, errs far less (1.8e-7 m).
		ENSURE(worst_radius < 1e-6);
		ENSURE(worst_position < 5e-5);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// Spinning free dumbbells
// ---------------------------------------------------------------------------------------------

#define DUMBBELLS 5

// Dumbbell b: masses m1, m2 [kg] on a spring of k [N/m] and rest length 0.8 m, stretched to l [m],
// no gravity, its centre of mass starting at c and moving at the velocity V [m/s], the two masses
// turning about it in the plane oblique_plane(b) at w [rad/s]. Each mass moves on a circle about
// the centre of mass (radii r1 = m2 l / (m1 + m2), r2 = m1 l / (m1 + m2)), so the spring's pull
// k (l - l0) is m1 w^2 r1 = mu w^2 l with the reduced mass mu = m1 m2 / (m1 + m2): equal masses
// m give k (l - l0) = m w^2 l / 2.
typedef struct dumbbell {
	double mass1, mass2, stiffness, length, omega, centre[3], velocity[3], e1[3], e2[3];
} dumbbell;

static dumbbell dumbbell_of(int b)
{
	dumbbell d;
	d.mass1 = 0.4 + 0.2 * b;
	d.mass2 = b == 1 ? d.mass1 : 1.0 - 0.1 * b;  // dumbbells 1 and 2 have equal masses
	d.stiffness = 50.0 + 15.0 * b;
	d.length = 0.9 + 0.1 * b;  // stretched by 12 % to 62 %
	const double mu = d.mass1 * d.mass2 / (d.mass1 + d.mass2);
	d.omega = sqrt(d.stiffness * (d.length - 0.8) / (mu * d.length));
	for (int c = 0; c < 3; c++) {
		d.centre[c] = 0.5 * b - 0.2 * c;
		d.velocity[c] = 0.1 * (b - 2) * (c + 1);
	}
	oblique_plane(b + 1, d.e1, d.e2);
	return d;
}

// Where mass `end` (0 or 1) of dumbbell d is at time t [s] (position [m] and velocity [m/s]).
static void dumbbell_motion(const dumbbell* d, int end, double t, double x[3], double v[3])
{
	const double total = d->mass1 + d->mass2;
	const double arm = end == 0 ? -d->mass2 * d->length / total : d->mass1 * d->length / total;
	const double c = cos(d->omega * t), s = sin(d->omega * t);
	for (int k = 0; k < 3; k++) {
		x[k] = d->centre[k] + d->velocity[k] * t + arm * (c * d->e1[k] + s * d->e2[k]);
		v[k] = d->velocity[k] + arm * d->omega * (-s * d->e1[k] + c * d->e2[k]);
	}
}

// Particles 2 b and 2 b + 1 and spring b for b < DUMBBELLS: five springs, over the four-wide and
// the scalar spring loops.
static sm_model* spinning_dumbbells(void)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&md, NULL);
	for (int b = 0; model != NULL && b < DUMBBELLS; b++) {
		const dumbbell d = dumbbell_of(b);
		sm_particle_def p[2] = {sm_default_particle_def(), sm_default_particle_def()};
		p[0].mass = d.mass1;
		p[1].mass = d.mass2;
		for (int end = 0; end < 2; end++)
			dumbbell_motion(&d, end, 0.0, p[end].position, p[end].velocity);
		sm_spring_def s = sm_default_spring_def();
		s.a = 2 * b;
		s.b = 2 * b + 1;
		s.rest_length = 0.8;
		s.stiffness = d.stiffness;
		if (sm_model_add_particle(model, &p[0], NULL) != SM_OK ||
		    sm_model_add_particle(model, &p[1], NULL) != SM_OK ||
		    sm_model_add_spring(model, &s, NULL) != SM_OK) {
			sm_model_destroy(model);
			return NULL;
		}
	}
	return model;
}

// Total angular momentum about the origin, sum m x x v [kg m^2/s], of the dumbbells.
static void dumbbells_angular_momentum(const double* x, const double* v, double L[3])
{
	L[0] = L[1] = L[2] = 0.0;
	for (int b = 0; b < DUMBBELLS; b++) {
		const dumbbell d = dumbbell_of(b);
		for (int end = 0; end < 2; end++) {
			const double m = end == 0 ? d.mass1 : d.mass2;
			const double* xi = x + 3 * (2 * b + end);
			const double* vi = v + 3 * (2 * b + end);
			L[0] += m * (xi[1] * vi[2] - xi[2] * vi[1]);
			L[1] += m * (xi[2] * vi[0] - xi[0] * vi[2]);
			L[2] += m * (xi[0] * vi[1] - xi[1] * vi[0]);
		}
	}
}

// A free dumbbell set spinning at the angular speed its stretched spring holds keeps its length
// and turns steadily while its centre of mass drifts at constant velocity; the angular momentum
// of all the dumbbells about the origin stays constant. Ten turns of the slowest (w from 4.4 to
// 10.3 rad/s), every 1/16 turn of it.
static int test_spinning_dumbbells_keep_their_length_and_angular_momentum(void)
{
	sm_model* model = spinning_dumbbells();
	ENSURE(model != NULL);
	double slowest = INFINITY;
	for (int b = 0; b < DUMBBELLS; b++)
		slowest = fmin(slowest, dumbbell_of(b).omega);
	const double duration = 10.0 * 2.0 * pi / slowest;
	for (int which = 0; which < INTEGRATOR_COUNT; which++) {
		const sm_simulation_def def = integrator_def(which);
		sm_simulation* sim = sm_simulation_create(model, &def, NULL);
		ENSURE(sim != NULL);
		double L0[3], scale = 0.0;
		dumbbells_angular_momentum(sm_simulation_positions(sim), sm_simulation_velocities(sim), L0);
		for (int c = 0; c < 3; c++)
			scale += L0[c] * L0[c];
		scale = sqrt(scale);
		double worst_length = 0.0, worst_position = 0.0, worst_momentum = 0.0;
		for (int i = 1; i <= 160; i++) {
			const double t = duration * i / 160.0;
			ENSURE_STATUS(sm_simulation_advance(sim, t), SM_OK);
			const double* x = sm_simulation_positions(sim);
			const double* v = sm_simulation_velocities(sim);
			for (int b = 0; b < DUMBBELLS; b++) {
				const dumbbell d = dumbbell_of(b);
				double length2 = 0.0;
				for (int c = 0; c < 3; c++) {
					const double dc = x[3 * (2 * b + 1) + c] - x[3 * (2 * b) + c];
					length2 += dc * dc;
				}
				worst_length = worst_of(worst_length, fabs(sqrt(length2) - d.length));
				for (int end = 0; end < 2; end++) {
					double xe[3], ve[3], e2 = 0.0;
					dumbbell_motion(&d, end, t, xe, ve);
					for (int c = 0; c < 3; c++)
						e2 += (x[3 * (2 * b + end) + c] - xe[c]) * (x[3 * (2 * b + end) + c] - xe[c]);
					worst_position = worst_of(worst_position, sqrt(e2));
				}
			}
			double L[3];
			dumbbells_angular_momentum(x, v, L);
			for (int c = 0; c < 3; c++)
				worst_momentum = worst_of(worst_momentum, fabs(L[c] - L0[c]));
		}
		printf("  %-8s largest length error %.3e m, position error %.3e m, angular momentum %.3e of %.3g "
		       "kg m^2/s, %ld steps\n",
		       integrator_name(which), worst_length, worst_position, worst_momentum, scale,
		       (long)sm_simulation_statistics(sim).steps);
		// About 6000 BDF steps (3400 Adams) add up as on the whirling bobs: about 1.5e-5 m of phase
		// (measured) and 4e-7 m of length. The angular momentum, quadratic in the state, drifts by the
		// same relative error, 5e-7 of its size (measured with BDF): 3e-6 allows for other rounding.
		ENSURE(worst_length < 2e-6);
		ENSURE(worst_position < 5e-5);
		ENSURE(worst_momentum < 3e-6 * scale);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// Spherical elastic pendulums
// ---------------------------------------------------------------------------------------------

#define ELASTIC_PENDULUMS 5

// Pendulum b: a bob of m [kg] on a spring of k [N/m] and rest length 1 m from a fixed pivot p_b,
// under gravity (0, 0, -9.81) m/s^2, pulled out sideways and down and thrown across: it swings
// in 3-D while the spring stretches and shortens. Pendulums 0 and 3 are tuned to the 2:1 resonance
// k / m = 4 g / (l0 + m g / k), i.e. k = 3 m g / l0, where the springing and the swinging trade
// their energy back and forth.
static sm_model* elastic_pendulums(void)
{
	const double g = 9.81;
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = -g;
	sm_model* model = sm_model_create(&md, NULL);
	for (int b = 0; model != NULL && b < ELASTIC_PENDULUMS; b++) {
		sm_particle_def pivot = sm_default_particle_def();
		pivot.motion = SM_PARTICLE_FIXED;
		pivot.position[0] = 2.0 * b;
		pivot.position[1] = 0.3 * b;
		pivot.position[2] = 0.5 - 0.2 * b;
		sm_particle_def bob = sm_default_particle_def();
		bob.mass = 0.5 + 0.3 * b;
		const double k = b % 3 == 0 ? 3.0 * bob.mass * g : 20.0 + 10.0 * b;
		bob.position[0] = pivot.position[0] + 0.4 + 0.1 * b;
		bob.position[1] = pivot.position[1] - 0.2;
		bob.position[2] = pivot.position[2] - 1.2 - 0.1 * b;
		bob.velocity[0] = 0.2;
		bob.velocity[1] = 1.0 + 0.2 * b;
		bob.velocity[2] = -0.3;
		sm_spring_def s = sm_default_spring_def();
		s.a = 2 * b;
		s.b = 2 * b + 1;
		s.rest_length = 1.0;
		s.stiffness = k;
		if (sm_model_add_particle(model, &pivot, NULL) != SM_OK ||
		    sm_model_add_particle(model, &bob, NULL) != SM_OK ||
		    sm_model_add_spring(model, &s, NULL) != SM_OK) {
			sm_model_destroy(model);
			return NULL;
		}
	}
	return model;
}

// The vertical component of a pendulum's angular momentum about its pivot, m ((x - p) x v)_z
// [kg m^2/s], and its energy, m |v|^2 / 2 + k (L - l0)^2 / 2 + m g z [J].
static void pendulum_invariants(const sm_model* model, const double* x, const double* v, int b, double* Lz,
                                double* energy)
{
	sm_particle_def pivot, bob;
	sm_spring_def s;
	sm_model_get_particle(model, 2 * b, &pivot);
	sm_model_get_particle(model, 2 * b + 1, &bob);
	sm_model_get_spring(model, b, &s);
	const double* xb = x + 3 * (2 * b + 1);
	const double* vb = v + 3 * (2 * b + 1);
	const double d[3] = {xb[0] - pivot.position[0], xb[1] - pivot.position[1], xb[2] - pivot.position[2]};
	*Lz = bob.mass * (d[0] * vb[1] - d[1] * vb[0]);
	const double stretch = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - s.rest_length;
	*energy = 0.5 * bob.mass * (vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2]) +
	          0.5 * s.stiffness * stretch * stretch + bob.mass * 9.81 * xb[2];
}

// Gravity exerts no torque about the vertical through a pivot and the spring pulls the bob
// straight towards it, so each spherical elastic pendulum keeps the vertical component of its
// angular momentum about its pivot, and its energy, however the resonant ones trade springing
// for swinging. Over 10 s (about 4 swings and 10 oscillations of
// the spring), every 0.05 s.
static int test_elastic_pendulums_keep_their_energy_and_vertical_angular_momentum(void)
{
	sm_model* model = elastic_pendulums();
	ENSURE(model != NULL);
	for (int which = 0; which < INTEGRATOR_COUNT; which++) {
		const sm_simulation_def def = integrator_def(which);
		sm_simulation* sim = sm_simulation_create(model, &def, NULL);
		ENSURE(sim != NULL);
		double Lz0[ELASTIC_PENDULUMS], energy0[ELASTIC_PENDULUMS], Lz_scale[ELASTIC_PENDULUMS];
		double energy_scale[ELASTIC_PENDULUMS];
		for (int b = 0; b < ELASTIC_PENDULUMS; b++) {
			pendulum_invariants(model, sm_simulation_positions(sim), sm_simulation_velocities(sim), b,
			                    &Lz0[b], &energy0[b]);
			Lz_scale[b] = fabs(Lz0[b]);
			energy_scale[b] = 0.0;
		}
		double worst_Lz = 0.0, worst_energy = 0.0;
		for (int i = 1; i <= 200; i++) {
			ENSURE_STATUS(sm_simulation_advance(sim, 0.05 * i), SM_OK);
			const double* x = sm_simulation_positions(sim);
			const double* v = sm_simulation_velocities(sim);
			for (int b = 0; b < ELASTIC_PENDULUMS; b++) {
				double Lz, energy;
				pendulum_invariants(model, x, v, b, &Lz, &energy);
				const double* vb = v + 3 * (2 * b + 1);
				sm_particle_def bob;
				sm_model_get_particle(model, 2 * b + 1, &bob);
				energy_scale[b] =
				    fmax(energy_scale[b], 0.5 * bob.mass * (vb[0] * vb[0] + vb[1] * vb[1] + vb[2] * vb[2]));
				worst_Lz = worst_of(worst_Lz, fabs(Lz - Lz0[b]) / Lz_scale[b]);
				worst_energy = worst_of(worst_energy, fabs(energy - energy0[b]) / energy_scale[b]);
			}
		}
		printf("  %-8s largest relative drift: angular momentum %.3e, energy %.3e, %ld steps\n",
		       integrator_name(which), worst_Lz, worst_energy, (long)sm_simulation_statistics(sim).steps);
		// Relative drifts of the accumulated local error, 1e-10 per step over some 3500 steps at the
		// most (measured 7e-8 with BDF): 1e-6, the bound of the energy test of the simulation tests.
		ENSURE(worst_Lz < 1e-6);
		ENSURE(worst_energy < 1e-6);
		sm_simulation_destroy(sim);
	}
	sm_model_destroy(model);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// The pendulum at large amplitude
// ---------------------------------------------------------------------------------------------

// The complete elliptic integral of the first kind K(k) = pi / (2 agm(1, sqrt(1 - k^2))), the
// arithmetic-geometric mean converging quadratically (Abramowitz and Stegun 17.6).
static double elliptic_k(double k)
{
	double a = 1.0, b = sqrt(1.0 - k * k);
	for (int i = 0; i < 40 && fabs(a - b) > 1e-16 * a; i++) {
		const double next = 0.5 * (a + b);
		b = sqrt(a * b);
		a = next;
	}
	return pi / (a + b);
}

#define PENDULUM_G 9.81         // [m/s^2]
#define PENDULUM_LENGTH 1.0     // [m]
#define PENDULUM_MASS 1.0       // [kg]
#define PENDULUM_STIFFNESS 1e8  // [N/m]

// The pendulum of the tests below: a bob of PENDULUM_MASS at rest at theta0 from the downward
// vertical under a fixed pivot (particle 0), on a rest-length spring of PENDULUM_STIFFNESS and rest
// length PENDULUM_LENGTH, critically damped along it, stretched to carry the bob's weight across
// it; gravity PENDULUM_G along -z. NULL if the model cannot be built.
static sm_model* stiff_pendulum(double theta0)
{
	const double g = PENDULUM_G, length = PENDULUM_LENGTH, m = PENDULUM_MASS, k = PENDULUM_STIFFNESS;
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = -g;
	sm_model* model = sm_model_create(&md, NULL);
	if (model == NULL)
		return NULL;
	sm_particle_def pivot = sm_default_particle_def();
	pivot.motion = SM_PARTICLE_FIXED;
	sm_particle_def bob = sm_default_particle_def();
	bob.mass = m;
	const double r0 = length + m * g * cos(theta0) / k;
	bob.position[0] = r0 * sin(theta0);
	bob.position[2] = -r0 * cos(theta0);
	sm_spring_def s = sm_default_spring_def();
	s.a = 0;
	s.b = 1;
	s.rest_length = length;
	s.stiffness = k;
	s.damping = 2.0 * sqrt(k * m);
	if (sm_model_add_particle(model, &pivot, NULL) != SM_OK ||
	    sm_model_add_particle(model, &bob, NULL) != SM_OK || sm_model_add_spring(model, &s, NULL) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// A simple pendulum released from rest at theta0 from the downward vertical swings with the period
// T = 4 sqrt(L / g) K(sin(theta0 / 2)) (Landau and Lifshitz, Mechanics, section 11, problem 1):
// it passes below its pivot at T / 4 + j T / 2 and comes to rest at j T / 2, alternately at
// -theta0 and theta0. The rod is a rest-length spring of k = 1e8 N/m, 1 m long, under a 1 kg bob,
// started at the length at which it carries the bob's weight across it, m g cos(theta0) (so no
// axial oscillation starts); its tension m g (3 cos(theta) - 2 cos(theta0)) stretches it by at
// most 5 m g / k = 4.9e-7 m, which changes the period by a like fraction, some 5e-7.
// The rod's damping, critical for its axial mode (2 sqrt(k m)), lets BDF step over that mode; it
// pulls along the rod only (no torque about the pivot) with kd dL/dt, dL/dt <= 3 m g |theta'| / k
// = 1.6e-6 m/s, which stretches the rod by a further 3e-10 m and dissipates at most 5e-8 W. Beyond
// 90 degrees the rod is compressed near the turning points, where the reduced solvers' definite
// Jacobian drops its negative geometric stiffness. Two periods at 60, 120 and 150 degrees.
static int test_a_stiff_pendulum_swings_with_the_elliptic_integral_period(void)
{
	const double g = PENDULUM_G, length = PENDULUM_LENGTH;
	const double degrees[] = {60.0, 120.0, 150.0};
	for (size_t a = 0; a < sizeof degrees / sizeof degrees[0]; a++) {
		const double theta0 = degrees[a] * pi / 180.0;
		const double period = 4.0 * sqrt(length / g) * elliptic_k(sin(theta0 / 2.0));
		sm_model* model = stiff_pendulum(theta0);
		ENSURE(model != NULL);
		// The fastest the bob moves, at the bottom, and its tangential acceleration at rest.
		const double fastest = sqrt(2.0 * g * length * (1.0 - cos(theta0)));
		const double turning = g * sin(theta0);
		for (int which = 0; which < INTEGRATOR_COUNT - 1; which++) {  // Adams cannot take the stiff rod
			const sm_simulation_def def = integrator_def(which);
			sm_simulation* sim = sm_simulation_create(model, &def, NULL);
			ENSURE(sim != NULL);
			// The time by which the bob is early or late: its distance from the vertical when it
			// should pass below the pivot over its speed there, and its speed when it should be at
			// rest over its acceleration there.
			double worst = 0.0;
			for (int j = 1; j <= 8; j++) {
				ENSURE_STATUS(sm_simulation_advance(sim, j * period / 4.0), SM_OK);
				const double* x = sm_simulation_positions(sim);
				const double* v = sm_simulation_velocities(sim);
				ENSURE(x[1] == 0.0 && v[1] == 0.0);
				if (j % 2 == 1) {
					worst = worst_of(worst, fabs(x[3]) / fastest);
				} else {
					worst = worst_of(worst, hypot(v[3], v[5]) / turning);
					// At rest the amplitude carries the integration's error (measured up to 1e-6 m);
					// the rod's compression, m g |cos(theta0)| / k, and a timing error dt, which
					// moves the bob by g sin(theta0) dt^2 / 2, are below 1e-7 m.
					ENSURE_NEAR(x[3], (j % 4 == 0 ? 1.0 : -1.0) * length * sin(theta0), 1e-5);
				}
			}
			printf("  %3.0f degrees, %-8s period %.6f s, largest timing error %.3e of a period, %ld steps\n",
			       degrees[a], integrator_name(which), period, worst / period,
			       (long)sm_simulation_statistics(sim).steps);
			// The rod's stretch shifts the times by some 5 m g / (k L) = 5e-7 of a period, and the
			// 8000 to 30 000 steps, each allowed 1e-10 of a state of speeds up to 5.4 m/s, add up to
			// a few 1e-6 s (measured 2e-7 to 2e-6 of a period, the most with dense and klu).
			ENSURE(worst < 5e-6 * period);
			sm_simulation_destroy(sim);
		}
		sm_model_destroy(model);
	}
	return 0;
}

// The same pendulum at 120 degrees over eight periods with the default options (rtol 1e-6, atol
// 1e-8 m and 1e-6 m/s, the solver auto picks: dense, for one free particle). The stiff rod's
// direction turns with the swing, and a Newton matrix kept from earlier steps (as CVODE keeps it
// by default, and klu still does) makes Newton's iteration fail again and again (2300 convergence
// failures) and end on inaccurate iterates: the bob ran 2.4e-2 of a period off its time, with klu
// 2.3e-2. dense now forms its matrix at every step: 9.1e-4 of a period, pcg (which evaluates its
// Jacobian at every step too) 5.4e-4, the error of some 12 000 steps each allowed 1e-6 of speeds
// up to 5.4 m/s.
static int test_a_stiff_pendulum_keeps_time_at_the_default_options(void)
{
	const double g = PENDULUM_G, length = PENDULUM_LENGTH, theta0 = 120.0 * pi / 180.0;
	const double period = 4.0 * sqrt(length / g) * elliptic_k(sin(theta0 / 2.0));
	sm_model* model = stiff_pendulum(theta0);
	ENSURE(model != NULL);
	const double fastest = sqrt(2.0 * g * length * (1.0 - cos(theta0)));
	sm_simulation* sim = sm_simulation_create(model, NULL, NULL);
	ENSURE(sim != NULL);
	double worst = 0.0;
	for (int j = 1; j <= 32; j += 2) {
		ENSURE_STATUS(sm_simulation_advance(sim, j * period / 4.0), SM_OK);
		worst = worst_of(worst, fabs(sm_simulation_positions(sim)[3]) / fastest);
	}
	printf("  %s: largest timing error %.3e of a period, %ld steps, %ld convergence failures\n",
	       sm_linear_solver_name(sm_simulation_solver(sim)), worst / period,
	       (long)sm_simulation_statistics(sim).steps,
	       (long)sm_simulation_statistics(sim).convergence_failures);
	ENSURE(worst < 2e-3 * period);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_bobs_whirl_steadily_on_their_circles);
	RUN_TEST(test_spinning_dumbbells_keep_their_length_and_angular_momentum);
	RUN_TEST(test_elastic_pendulums_keep_their_energy_and_vertical_angular_momentum);
	RUN_TEST(test_a_stiff_pendulum_swings_with_the_elliptic_integral_period);
	RUN_TEST(test_a_stiff_pendulum_keeps_time_at_the_default_options);
	return TEST_SUMMARY();
}

// Structures built from particles and springs: ropes, sheets and blocks (meshes live in
// mesh.c), and the helpers that select their particles.
//
// Every builder first checks its definition and the sizes it will create, then appends. If
// appending fails half-way (a spring the model rejects, memory), the model is cut back to the
// particle and spring counts it had before the call: nothing half-built stays.
#include "structures_internal.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

sm_spring_material sm_default_spring_material(void)
{
	sm_spring_material m;
	memset(&m, 0, sizeof m);
	m.stiffness_scaling = SM_PER_STRAIN;
	m.damping_scaling = SM_PER_STRAIN;
	m.break_strain = INFINITY;
	return m;
}

static sm_spring_material strain_material(double stiffness, double damping)
{
	sm_spring_material m = sm_default_spring_material();
	m.stiffness = stiffness;
	m.damping = damping;
	return m;
}

sm_rope_def sm_default_rope_def(void)
{
	sm_rope_def d;
	memset(&d, 0, sizeof d);
	d.end[0] = 1.0;
	d.segments = 10;
	d.mass = 1.0;
	d.structural = strain_material(1000.0, 0.0);
	d.bending = sm_default_spring_material();
	return d;
}

sm_sheet_def sm_default_sheet_def(void)
{
	sm_sheet_def d;
	memset(&d, 0, sizeof d);
	d.edge_u[0] = 1.0;
	d.edge_v[1] = 1.0;
	d.nu = 16;
	d.nv = 16;
	d.mass = 1.0;
	d.structural = strain_material(1000.0, 2.0);
	d.shear = strain_material(1000.0, 2.0);
	d.bend = strain_material(50.0, 2.0);
	return d;
}

sm_block_def sm_default_block_def(void)
{
	sm_block_def d;
	memset(&d, 0, sizeof d);
	d.size[0] = d.size[1] = d.size[2] = 1.0;
	d.nu = d.nv = d.nw = 4;
	d.mass = 1.0;
	d.edge = strain_material(1000.0, 0.0);
	d.face_diagonal = strain_material(1000.0, 0.0);
	d.body_diagonal = strain_material(1000.0, 0.0);
	return d;
}

int32_t sm_structure_particle(const sm_structure* s, int32_t i, int32_t j, int32_t k)
{
	if (s == NULL || i < 0 || j < 0 || k < 0 || j >= s->shape[0] || i >= s->shape[1] || k >= s->shape[2])
		return -1;
	// Each partial index is below INT32_MAX before it is multiplied again, so that no product
	// overflows 64 bits even for a hand-made shape of 2^31 - 1 cubed.
	int64_t index = (int64_t)k * s->shape[1] + i;
	if (index > INT32_MAX)
		return -1;
	index = index * s->shape[0] + j + s->first_particle;
	return index >= 0 && index <= INT32_MAX ? (int32_t)index : -1;
}

// ---------------------------------------------------------------------------------------------
// Shared steps of every builder.
// ---------------------------------------------------------------------------------------------

bool sm_structure_material_present(const sm_spring_material* m)
{
	return m->keep_when_zero || m->stiffness != 0.0 || m->damping != 0.0;
}

sm_status sm_structure_check_material(sm_model* model, const char* what, const char* group,
                                      const sm_spring_material* m, bool sections)
{
	if (!isfinite(m->stiffness) || m->stiffness < 0.0)
		return sm_model_fail(model, isfinite(m->stiffness) ? SM_ERROR_NEGATIVE : SM_ERROR_NOT_FINITE,
		                     "%s: %s stiffness = %g must be finite and >= 0", what, group, m->stiffness);
	if (!isfinite(m->damping) || m->damping < 0.0)
		return sm_model_fail(model, isfinite(m->damping) ? SM_ERROR_NEGATIVE : SM_ERROR_NOT_FINITE,
		                     "%s: %s damping = %g must be finite and >= 0", what, group, m->damping);
	const sm_scaling scalings[2] = {m->stiffness_scaling, m->damping_scaling};
	for (int k = 0; k < 2; k++) {
		const char* constant = k == 0 ? "stiffness" : "damping";
		if (scalings[k] != SM_ABSOLUTE && scalings[k] != SM_PER_STRAIN && scalings[k] != SM_PER_SECTION)
			return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "%s: %s %s scaling = %d is not known",
			                     what, group, constant, (int)scalings[k]);
		if (scalings[k] == SM_PER_SECTION && !sections)
			return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
			                     "%s: %s %s per section: a %s has no cross-section (give it per strain)",
			                     what, group, constant, what);
	}
	if (isnan(m->break_strain) || !(m->break_strain > 0.0))
		return sm_model_fail(model, isnan(m->break_strain) ? SM_ERROR_NOT_FINITE : SM_ERROR_NEGATIVE,
		                     "%s: %s break strain = %g must be > 0 (INFINITY for never)", what, group,
		                     m->break_strain);
	if (!(m->break_strain > SM_MIN_BREAK_STRAIN)) {
		char rule[SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY];
		sm_break_strain_floor_text(m->break_strain, rule);
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "%s: %s %s, and the springs break at rest",
		                     what, group, rule);
	}
	return SM_OK;
}

sm_status sm_structure_check_vector(sm_model* model, const char* what, const char* field, const double v[3])
{
	for (int c = 0; c < 3; c++)
		if (!isfinite(v[c]))
			return sm_model_fail(model, SM_ERROR_NOT_FINITE, "%s: %s[%d] = %g is not finite", what, field, c,
			                     v[c]);
	return SM_OK;
}

sm_status sm_structure_check_size(sm_model* model, const char* what, int64_t particles, int64_t springs)
{
	if (particles > SM_STRUCTURE_MAX_ELEMENTS || springs > SM_STRUCTURE_MAX_ELEMENTS)
		return sm_model_fail(
		    model, SM_ERROR_INVALID_ARGUMENT,
		    "%s: %lld particles and %lld springs exceed the limit of %d of each per structure", what,
		    (long long)particles, (long long)springs, SM_STRUCTURE_MAX_ELEMENTS);
	if ((int64_t)model->particle_count + particles > SM_STRUCTURE_MAX_ELEMENTS * 4LL ||
	    (int64_t)model->spring_count + springs > SM_STRUCTURE_MAX_ELEMENTS * 4LL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "%s: the model would grow past %lld elements",
		                     what, SM_STRUCTURE_MAX_ELEMENTS * 4LL);
	return SM_OK;
}

// Cuts the model back to the counts it had before a failed builder call. Arrays only ever grow
// and earlier entries are never moved, so the particles and springs below the counts are
// intact; only the free-particle numbering must follow the particle count (the builders' particles
// carry no load, so the count of loaded particles stays).
void sm_structure_truncate(sm_model* m, int32_t particles, int32_t springs)
{
	m->particle_count = particles;
	m->spring_count = springs;
	int32_t count = 0;
	for (int32_t i = 0; i < m->particle_count; i++)
		m->free_index[i] = m->motion[i] == SM_PARTICLE_FREE ? count++ : -1;
	m->free_count = count;
}

sm_status sm_structure_add_particle(sm_model* model, const char* what, double mass, const double position[3])
{
	sm_particle_def p = sm_default_particle_def();
	p.mass = mass;
	memcpy(p.position, position, sizeof p.position);
	sm_status st = sm_model_add_particle(model, &p, NULL);
	if (st != SM_OK) {
		char inner[SM_ERROR_MESSAGE_CAPACITY];
		snprintf(inner, sizeof inner, "%s", sm_model_last_error(model));
		sm_model_fail(model, st, "%s: %s", what, inner);
	}
	return st;
}

// Spring lengths the model can hold: their squares (model.c computes L = sqrt(d . d)) must be
// finite and normal doubles, so L lies between sqrt(DBL_MIN) = 1.5e-154 m and sqrt(DBL_MAX) =
// 1.3e154 m. A structure's spacing outside that range comes from its extents and counts: the
// message names them (`inputs`), not the inf or 0 their squares would give.
sm_status sm_structure_add_spring(sm_model* model, const char* what, const char* inputs, const char* group,
                                  int32_t a, int32_t b, const sm_spring_material* m, double measure)
{
	sm_spring_def s = sm_default_spring_def();
	const double* xa = model->position + 3 * (size_t)a;
	const double* xb = model->position + 3 * (size_t)b;
	const double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
	const double squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
	// Coincident particles (d = 0) are the builders' own concern: a sheet's or block's grid
	// refuses them, a rope without length keeps them (rest length 0, absolute constants only).
	if (!isfinite(squared))
		return sm_model_fail(
		    model, SM_ERROR_NOT_FINITE,
		    "%s: %s spring between particles %d and %d would be longer than %.2g m, where its squared "
		    "length overflows: %s make the structure too large",
		    what, group, (int)a, (int)b, sqrt(DBL_MAX), inputs);
	if (squared < DBL_MIN && (d[0] != 0.0 || d[1] != 0.0 || d[2] != 0.0)) {
		// The length from components divided by the largest, whose squares cannot underflow.
		const double largest = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
		const double u[3] = {d[0] / largest, d[1] / largest, d[2] / largest};
		return sm_model_fail(
		    model, SM_ERROR_INVALID_ARGUMENT,
		    "%s: %s spring between particles %d and %d would be %.3g m long, below %.2g m, where its "
		    "squared length underflows: %s make the grid too fine",
		    what, group, (int)a, (int)b, largest * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]),
		    sqrt(DBL_MIN), inputs);
	}
	if (m->stiffness_scaling == SM_PER_SECTION || m->damping_scaling == SM_PER_SECTION) {
		s.section = measure / sqrt(squared);
		if (!isfinite(s.section) || !(s.section > 0.0))
			return sm_model_fail(
			    model, isfinite(s.section) ? SM_ERROR_INVALID_ARGUMENT : SM_ERROR_NOT_FINITE,
			    "%s: %s spring between particles %d and %d: its section, the %s of the cells it stands "
			    "for over its length, %s: %s make the cells too %s for per-section constants",
			    what, group, (int)a, (int)b, strcmp(what, "block") == 0 ? "volume" : "area",
			    isfinite(s.section) ? "underflows to 0" : "overflows", inputs,
			    isfinite(s.section) ? "small" : "large");
	}
	s.a = a;
	s.b = b;
	s.stiffness = m->stiffness;
	s.stiffness_scaling = m->stiffness_scaling;
	s.damping = m->damping;
	s.damping_scaling = m->damping_scaling;
	s.break_strain = m->break_strain;
	sm_status st = sm_model_add_spring(model, &s, NULL);
	if (st != SM_OK) {
		char inner[SM_ERROR_MESSAGE_CAPACITY];
		snprintf(inner, sizeof inner, "%s", sm_model_last_error(model));
		sm_model_fail(model, st, "%s: %s spring between particles %d and %d: %s", what, group, (int)a, (int)b,
		              inner);
	}
	return st;
}

static sm_status check_distribution(sm_model* model, const char* what, sm_mass_distribution distribution)
{
	if (distribution != SM_MASS_EVEN && distribution != SM_MASS_LUMPED)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "%s: mass distribution = %d is not known",
		                     what, (int)distribution);
	return SM_OK;
}

// The share of a grid cell's area or volume that a spring from grid point `at` along `offset`
// stands for: the cells on both sides of it, or only one side where it runs along the boundary.
// Along each axis the spring does not advance on (offset 0), a spring on the first or last grid
// line has cells on one side only: half. So uniformly stretched, the springs of a group carry
// exactly the force per unit width (or area) that their constant gives, whatever the grid.
static double boundary_share(const int offset[], const int64_t at[], const int64_t counts[], int axes)
{
	double share = 1.0;
	for (int axis = 0; axis < axes; axis++)
		if (offset[axis] == 0 && (at[axis] == 0 || at[axis] == counts[axis] - 1))
			share *= 0.5;
	return share;
}

// The mass [kg] of grid point `at` of a structure of `total` kg on a grid of counts[] points
// along each of its axes (sm_mass_distribution): the same for every point, or lumped, the share
// of the cells around it: a half for each axis along which it is on the boundary.
static double grid_point_mass(double total, sm_mass_distribution distribution, const int64_t at[],
                              const int64_t counts[], int axes)
{
	// A point's share of the cells around it is a spring's that advances along no axis.
	static const int no_offset[3] = {0, 0, 0};
	double points = 1.0, cells = 1.0;
	for (int axis = 0; axis < axes; axis++) {
		points *= (double)counts[axis];
		cells *= (double)(counts[axis] - 1);
	}
	return distribution == SM_MASS_LUMPED ? total * boundary_share(no_offset, at, counts, axes) / cells
	                                      : total / points;
}

static sm_status check_mass(sm_model* model, const char* what, double mass)
{
	if (!isfinite(mass))
		return sm_model_fail(model, SM_ERROR_NOT_FINITE, "%s: mass = %g is not finite", what, mass);
	if (!(mass > 0.0))
		return sm_model_fail(model, SM_ERROR_NONPOSITIVE_MASS, "%s: mass = %g must be > 0", what, mass);
	return SM_OK;
}

void sm_structure_fill_out(sm_structure* out, int32_t p0, int32_t s0, const sm_model* model, int32_t n0,
                           int32_t n1, int32_t n2, const int32_t group_springs[3])
{
	if (out == NULL)
		return;
	for (int g = 0; g < 3; g++)
		out->group_spring_count[g] = group_springs[g];
	out->first_particle = p0;
	out->particle_count = model->particle_count - p0;
	out->first_spring = s0;
	out->spring_count = model->spring_count - s0;
	out->shape[0] = n0;
	out->shape[1] = n1;
	out->shape[2] = n2;
}

// Two grid neighbours at the same position: a grid spacing below the rounding of the
// coordinates (a 1e-10 m spacing 1e10 m from the origin) collapses the grid, and its springs
// would have no length. The grid has shape[0] x shape[1] x shape[2] points from particle p0 on,
// numbered as in sm_structure_particle. Fails naming the first such pair.
//
// Neighbours along each axis are compared and, with `diagonals` (a sheet), across both
// diagonals of each cell: a sheet's edges may be nearly parallel (down to a sine of 1e-12), and
// then a cell's diagonal edge_v / (nv - 1) - edge_u / (nu - 1) can be below the rounding where
// its sides are not. A block's axes are orthogonal and each coordinate follows one index, so its
// diagonal neighbours coincide only where those along its axes do. Points two apart along a
// grid line coincide only if the one between does too: each coordinate, rounded from a sum
// that grows (or falls) along the line, never turns back.
static sm_status check_grid_distinct(sm_model* model, const char* what, int32_t p0, const int64_t shape[3],
                                     bool diagonals)
{
	// Offsets (column, row, layer) of the neighbours compared: the axes, then the diagonals.
	static const int offsets[5][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {-1, 1, 0}};
	const int64_t stride[3] = {1, shape[0], shape[0] * shape[1]};
	for (int64_t k = 0; k < shape[2]; k++)
		for (int64_t i = 0; i < shape[1]; i++)
			for (int64_t j = 0; j < shape[0]; j++) {
				const int64_t at[3] = {j, i, k}, p = p0 + j + i * stride[1] + k * stride[2];
				for (int o = 0; o < (diagonals ? 5 : 3); o++) {
					int64_t q = p0;
					bool inside = true;
					for (int axis = 0; axis < 3; axis++) {
						const int64_t to = at[axis] + offsets[o][axis];
						inside = inside && to >= 0 && to < shape[axis];
						q += to * stride[axis];
					}
					if (!inside)
						continue;
					const double* x = model->position + 3 * p;
					const double* y = model->position + 3 * q;
					if (x[0] == y[0] && x[1] == y[1] && x[2] == y[2])
						return sm_model_fail(
						    model, SM_ERROR_INVALID_ARGUMENT,
						    "%s: particles %lld and %lld coincide at (%g, %g, %g) m: %s", what, (long long)p,
						    (long long)q, x[0], x[1], x[2],
						    o < 3 ? "the grid spacing is below the resolution of the coordinates there"
							      : "the diagonal of the grid's cells is below the resolution of the "
							        "coordinates there (edge_u and edge_v nearly parallel)");
				}
			}
	return SM_OK;
}

// ---------------------------------------------------------------------------------------------
// Rope.
// ---------------------------------------------------------------------------------------------

sm_status sm_add_rope(sm_model* model, const sm_rope_def* def, sm_structure* out)
{
	static const char what[] = "rope";
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (def == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "rope: definition is NULL");
	sm_status st;
	if ((st = sm_structure_check_vector(model, what, "start", def->start)) != SM_OK ||
	    (st = sm_structure_check_vector(model, what, "end", def->end)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "structural", &def->structural, false)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "bending", &def->bending, false)) != SM_OK)
		return st;
	if (def->segments < 1)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "rope: segments = %d must be >= 1",
		                     (int)def->segments);
	const double dx = def->end[0] - def->start[0], dy = def->end[1] - def->start[1],
	             dz = def->end[2] - def->start[2];
	if (!isfinite(dx) || !isfinite(dy) || !isfinite(dz))
		return sm_model_fail(
		    model, SM_ERROR_NOT_FINITE,
		    "rope: start (%g, %g, %g) m and end (%g, %g, %g) m are too far apart: end - start is beyond "
		    "the largest double",
		    def->start[0], def->start[1], def->start[2], def->end[0], def->end[1], def->end[2]);
	// |end - start|, from the components divided by the largest where the squares would overflow
	// or underflow (a rope of 1e-200 m has a length, and with it a mass per length a mass).
	double length = sqrt(dx * dx + dy * dy + dz * dz);
	const double largest = fmax(fabs(dx), fmax(fabs(dy), fabs(dz)));
	if (largest > 0.0 && !(length >= sqrt(DBL_MIN) && length <= sqrt(DBL_MAX)))
		length = largest * sqrt((dx / largest) * (dx / largest) + (dy / largest) * (dy / largest) +
		                        (dz / largest) * (dz / largest));
	// A rope whose start is its end has springs of rest length 0. With absolute constants they
	// pull like zero-length springs (ks L u = ks d); per-strain constants E / l0 and a break strain
	// (L - l0) / l0 have no value there.
	const sm_spring_material* groups[2] = {&def->structural, &def->bending};
	static const char* const group_names[2] = {"structural", "bending"};
	for (int g = 0; g < 2 && length == 0.0; g++) {
		const sm_spring_material* m = groups[g];
		if (!sm_structure_material_present(m))
			continue;
		const char* needs = m->stiffness_scaling != SM_ABSOLUTE ? "per-strain stiffness (E / l0)"
		                    : m->damping_scaling != SM_ABSOLUTE ? "per-strain damping (c / l0)"
		                    : isfinite(m->break_strain)         ? "break strain ((L - l0) / l0)"
		                                                        : NULL;
		const char* instead = m->stiffness_scaling != SM_ABSOLUTE ? "an absolute stiffness"
		                      : m->damping_scaling != SM_ABSOLUTE ? "an absolute damping"
		                                                          : "none";
		if (needs != NULL)
			return sm_model_fail(
			    model, SM_ERROR_ZERO_REST_LENGTH,
			    "rope: start = end = (%g, %g, %g) m: its springs have rest length 0, and the %s "
			    "group's %s needs a rest length > 0: give it %s, or the rope a length",
			    def->start[0], def->start[1], def->start[2], group_names[g], needs, instead);
	}
	double total = def->mass;
	if (!isfinite(def->mass_per_length))
		return sm_model_fail(model, SM_ERROR_NOT_FINITE, "rope: mass per length = %g must be finite and >= 0",
		                     def->mass_per_length);
	if (def->mass_per_length < 0.0)
		return sm_model_fail(model, SM_ERROR_NEGATIVE, "rope: mass per length = %g must be finite and >= 0",
		                     def->mass_per_length);
	if (def->mass_per_length > 0.0) {
		total = def->mass_per_length * length;
		// A rope whose start is its end has no length to spread a mass per length over.
		if (!(total > 0.0) || !isfinite(total))
			return sm_model_fail(
			    model, isfinite(total) ? SM_ERROR_NONPOSITIVE_MASS : SM_ERROR_NOT_FINITE,
			    "rope: mass per length %g kg/m over the length %g m from start to end gives a "
			    "mass %s (give the mass instead)",
			    def->mass_per_length, length,
			    !isfinite(total) ? "beyond the largest double"
				: length > 0.0   ? "below the smallest double"
				                 : "of 0 kg, which must be finite and > 0");
	}
	if ((st = check_mass(model, what, total)) != SM_OK ||
	    (st = check_distribution(model, what, def->mass_distribution)) != SM_OK)
		return st;

	const int64_t n = (int64_t)def->segments + 1;
	const bool has_structural = sm_structure_material_present(&def->structural);
	const bool has_bending = sm_structure_material_present(&def->bending);
	const int64_t springs = (has_structural ? n - 1 : 0) + (has_bending ? n - 2 : 0);
	if ((st = sm_structure_check_size(model, what, n, springs)) != SM_OK)
		return st;

	const int32_t p0 = model->particle_count, s0 = model->spring_count;
	const int32_t made[3] = {has_structural ? (int32_t)(n - 1) : 0, has_bending ? (int32_t)(n - 2) : 0, 0};
	const int64_t rope_counts[1] = {n};
	for (int64_t p = 0; p < n && st == SM_OK; p++) {
		// The last particle at the end itself: start + 1 x (end - start) rounds to a neighbour of
		// the end for about a third of decimal ends and starts.
		const double t = (double)p / (double)def->segments;
		const double x[3] = {def->start[0] + t * dx, def->start[1] + t * dy, def->start[2] + t * dz};
		const int64_t at[1] = {p};
		st = sm_structure_add_particle(model, what,
		                               grid_point_mass(total, def->mass_distribution, at, rope_counts, 1),
		                               p + 1 < n ? x : def->end);
	}
	// Neighbours that coincide although the ends differ (a spacing below the rounding of the
	// coordinates) would give springs of rest length 0 among longer ones: refused as in a grid.
	const int64_t rope_shape[3] = {n, 1, 1};
	if (st == SM_OK && length > 0.0)
		st = check_grid_distinct(model, what, p0, rope_shape, false);
	static const char rope_inputs[] = "start, end and segments";
	for (int64_t p = 0; p < n && st == SM_OK; p++) {
		const int32_t a = p0 + (int32_t)p;
		if (has_structural && p + 1 < n)
			st = sm_structure_add_spring(model, what, rope_inputs, "structural", a, a + 1, &def->structural,
			                             0.0);
		if (st == SM_OK && has_bending && p + 2 < n)
			st = sm_structure_add_spring(model, what, rope_inputs, "bending", a, a + 2, &def->bending, 0.0);
	}
	if (st != SM_OK) {
		sm_structure_truncate(model, p0, s0);
		return st;
	}
	sm_structure_fill_out(out, p0, s0, model, (int32_t)n, 1, 1, made);
	return SM_OK;
}

// ---------------------------------------------------------------------------------------------
// Sheet.
// ---------------------------------------------------------------------------------------------

sm_status sm_add_sheet(sm_model* model, const sm_sheet_def* def, sm_structure* out)
{
	static const char what[] = "sheet";
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (def == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "sheet: definition is NULL");
	sm_status st;
	if ((st = sm_structure_check_vector(model, what, "origin", def->origin)) != SM_OK ||
	    (st = sm_structure_check_vector(model, what, "edge_u", def->edge_u)) != SM_OK ||
	    (st = sm_structure_check_vector(model, what, "edge_v", def->edge_v)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "structural", &def->structural, true)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "shear", &def->shear, true)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "bend", &def->bend, true)) != SM_OK ||
	    (st = check_mass(model, what, def->mass)) != SM_OK ||
	    (st = check_distribution(model, what, def->mass_distribution)) != SM_OK)
		return st;
	if (def->nu < 2 || def->nv < 2)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "sheet: nu = %d and nv = %d must both be >= 2",
		                     (int)def->nu, (int)def->nv);
	// The edges must span an area: |u x v| > 1e-12 |u| |v|, the sine of the angle between them
	// above 1e-12. Each edge is first divided by its largest component, so that neither the
	// cross product nor the lengths overflow or underflow (edges of 1e200 m or 1e-300 m).
	double u[3], v[3], u_max = 0.0, v_max = 0.0;
	for (int c = 0; c < 3; c++) {
		u_max = fmax(u_max, fabs(def->edge_u[c]));
		v_max = fmax(v_max, fabs(def->edge_v[c]));
	}
	if (u_max == 0.0 || v_max == 0.0)
		return sm_model_fail(
		    model, SM_ERROR_INVALID_ARGUMENT,
		    "sheet: %s = (0, 0, 0) m is zero: the sheet spans no area and its particles would "
		    "coincide",
		    u_max == 0.0 ? "edge_u" : "edge_v");
	for (int c = 0; c < 3; c++) {
		u[c] = def->edge_u[c] / u_max;
		v[c] = def->edge_v[c] / v_max;
	}
	const double normal[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
	                          u[0] * v[1] - u[1] * v[0]};
	const double area = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
	if (!(area > 1e-12 * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) *
	                 sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])))
		return sm_model_fail(
		    model, SM_ERROR_INVALID_ARGUMENT,
		    "sheet: edge_u = (%g, %g, %g) m and edge_v = (%g, %g, %g) m are parallel "
		    "(|edge_u x edge_v| <= 1e-12 |edge_u| |edge_v|): the sheet spans no area and its "
		    "particles would coincide",
		    def->edge_u[0], def->edge_u[1], def->edge_u[2], def->edge_v[0], def->edge_v[1], def->edge_v[2]);

	// The corners of the parallelogram must be doubles: its particles lie between them.
	static const char axis_names[3] = {'x', 'y', 'z'};
	for (int c = 0; c < 3; c++)
		if (!isfinite(def->origin[c] + def->edge_u[c]) || !isfinite(def->origin[c] + def->edge_v[c]) ||
		    !isfinite(def->origin[c] + def->edge_u[c] + def->edge_v[c]))
			return sm_model_fail(
			    model, SM_ERROR_NOT_FINITE,
			    "sheet: origin (%g, %g, %g) m plus edge_u (%g, %g, %g) m and edge_v (%g, %g, %g) m "
			    "reaches beyond the largest double along %c",
			    def->origin[0], def->origin[1], def->origin[2], def->edge_u[0], def->edge_u[1],
			    def->edge_u[2], def->edge_v[0], def->edge_v[1], def->edge_v[2], axis_names[c]);

	// The particles first: for counts up to 2^31 - 1 each, nu nv fits in 64 bits but the springs,
	// some 6 nu nv, do not.
	const int64_t nu = def->nu, nv = def->nv, n = nu * nv;
	if (n > SM_STRUCTURE_MAX_ELEMENTS)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
		                     "sheet: %d x %d particles exceed the limit of %d per structure", (int)nu,
		                     (int)nv, SM_STRUCTURE_MAX_ELEMENTS);
	const bool has[3] = {sm_structure_material_present(&def->structural),
	                     sm_structure_material_present(&def->shear),
	                     sm_structure_material_present(&def->bend)};
	const int64_t springs = (has[0] ? (nu - 1) * nv + nu * (nv - 1) : 0) +
	                        (has[1] ? 2 * (nu - 1) * (nv - 1) : 0) +
	                        (has[2] ? (nu - 2) * nv + nu * (nv - 2) : 0);
	if ((st = sm_structure_check_size(model, what, n, springs)) != SM_OK)
		return st;

	const int32_t p0 = model->particle_count, s0 = model->spring_count;
	const int64_t sheet_counts[2] = {nv, nu};
	for (int64_t i = 0; i < nv && st == SM_OK; i++) {
		for (int64_t j = 0; j < nu && st == SM_OK; j++) {
			const double s = (double)j / (double)(nu - 1), t = (double)i / (double)(nv - 1);
			double x[3];
			for (int c = 0; c < 3; c++)
				x[c] = def->origin[c] + s * def->edge_u[c] + t * def->edge_v[c];
			const int64_t at[2] = {i, j};
			st = sm_structure_add_particle(
			    model, what, grid_point_mass(def->mass, def->mass_distribution, at, sheet_counts, 2), x);
		}
	}
	const int64_t sheet_shape[3] = {nu, nv, 1};
	if (st == SM_OK)
		st = check_grid_distinct(model, what, p0, sheet_shape, true);
	// Per-section constants: each spring stands for the area of a grid cell (one spring of each
	// offset per cell), half of it along an edge of the sheet, and its section is that area over
	// its length (sm_scaling).
	const double cell_area = area * u_max * v_max / (double)((nu - 1) * (nv - 1));
	// Neighbour offsets (di, dj) and their group, in the benchmark cloth's order.
	static const int offsets[6][3] = {{0, 1, 0}, {1, 0, 0}, {1, 1, 1}, {1, -1, 1}, {0, 2, 2}, {2, 0, 2}};
	const sm_spring_material* groups[3] = {&def->structural, &def->shear, &def->bend};
	static const char* const group_names[3] = {"structural", "shear", "bend"};
	int32_t made[3] = {0, 0, 0};
	for (int64_t i = 0; i < nv && st == SM_OK; i++) {
		for (int64_t j = 0; j < nu && st == SM_OK; j++) {
			for (int o = 0; o < 6 && st == SM_OK; o++) {
				const int g = offsets[o][2];
				const int64_t a = i + offsets[o][0], b = j + offsets[o][1];
				if (!has[g] || a >= nv || b < 0 || b >= nu)
					continue;
				const int64_t at[2] = {i, j};
				st =
				    sm_structure_add_spring(model, what, "edge_u, edge_v, nu and nv", group_names[g],
					                        p0 + (int32_t)(i * nu + j), p0 + (int32_t)(a * nu + b), groups[g],
					                        cell_area * boundary_share(offsets[o], at, sheet_counts, 2));
				made[g]++;
			}
		}
	}
	if (st != SM_OK) {
		sm_structure_truncate(model, p0, s0);
		return st;
	}
	sm_structure_fill_out(out, p0, s0, model, def->nu, def->nv, 1, made);
	return SM_OK;
}

// ---------------------------------------------------------------------------------------------
// Block.
// ---------------------------------------------------------------------------------------------

sm_status sm_add_block(sm_model* model, const sm_block_def* def, sm_structure* out)
{
	static const char what[] = "block";
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (def == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "block: definition is NULL");
	sm_status st;
	if ((st = sm_structure_check_vector(model, what, "origin", def->origin)) != SM_OK ||
	    (st = sm_structure_check_vector(model, what, "size", def->size)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "edge", &def->edge, true)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "face_diagonal", &def->face_diagonal, true)) !=
	        SM_OK ||
	    (st = sm_structure_check_material(model, what, "body_diagonal", &def->body_diagonal, true)) !=
	        SM_OK ||
	    (st = check_mass(model, what, def->mass)) != SM_OK ||
	    (st = check_distribution(model, what, def->mass_distribution)) != SM_OK)
		return st;
	for (int c = 0; c < 3; c++)
		if (!(def->size[c] > 0.0))
			return sm_model_fail(model, SM_ERROR_NEGATIVE, "block: size[%d] = %g must be > 0", c,
			                     def->size[c]);
	for (int c = 0; c < 3; c++)
		if (!isfinite(def->origin[c] + def->size[c]))
			return sm_model_fail(model, SM_ERROR_NOT_FINITE,
			                     "block: origin[%d] + size[%d] = %g m + %g m is beyond the "
			                     "largest double",
			                     c, c, def->origin[c], def->size[c]);
	if (def->nu < 2 || def->nv < 2 || def->nw < 2)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
		                     "block: nu = %d, nv = %d and nw = %d must all be >= 2", (int)def->nu,
		                     (int)def->nv, (int)def->nw);

	const int64_t nu = def->nu, nv = def->nv, nw = def->nw;
	if (nu * nv > SM_STRUCTURE_MAX_ELEMENTS || nu * nv * nw > SM_STRUCTURE_MAX_ELEMENTS)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
		                     "block: %d x %d x %d particles exceed the limit of %d per structure", (int)nu,
		                     (int)nv, (int)nw, SM_STRUCTURE_MAX_ELEMENTS);
	const int64_t n = nu * nv * nw;
	const bool has[3] = {sm_structure_material_present(&def->edge),
	                     sm_structure_material_present(&def->face_diagonal),
	                     sm_structure_material_present(&def->body_diagonal)};
	const int64_t edges = (nu - 1) * nv * nw + nu * (nv - 1) * nw + nu * nv * (nw - 1);
	const int64_t faces =
	    2 * ((nu - 1) * (nv - 1) * nw + (nu - 1) * nv * (nw - 1) + nu * (nv - 1) * (nw - 1));
	const int64_t bodies = 4 * (nu - 1) * (nv - 1) * (nw - 1);
	const int64_t springs = (has[0] ? edges : 0) + (has[1] ? faces : 0) + (has[2] ? bodies : 0);
	if ((st = sm_structure_check_size(model, what, n, springs)) != SM_OK)
		return st;

	const int32_t p0 = model->particle_count, s0 = model->spring_count;
	const int64_t block_counts[3] = {nv, nu, nw};
	for (int64_t k = 0; k < nw && st == SM_OK; k++)
		for (int64_t i = 0; i < nv && st == SM_OK; i++)
			for (int64_t j = 0; j < nu && st == SM_OK; j++) {
				const double x[3] = {def->origin[0] + (double)j / (double)(nu - 1) * def->size[0],
				                     def->origin[1] + (double)i / (double)(nv - 1) * def->size[1],
				                     def->origin[2] + (double)k / (double)(nw - 1) * def->size[2]};
				const int64_t at[3] = {i, j, k};
				st = sm_structure_add_particle(
				    model, what, grid_point_mass(def->mass, def->mass_distribution, at, block_counts, 3), x);
			}
	const int64_t block_shape[3] = {nu, nv, nw};
	if (st == SM_OK)
		st = check_grid_distinct(model, what, p0, block_shape, false);
	// Per-section constants: as in a sheet, each spring stands for the volume of a cell, halved
	// for each face of the block it lies in.
	const double cell_volume = def->size[0] / (double)(nu - 1) * (def->size[1] / (double)(nv - 1)) *
	                           (def->size[2] / (double)(nw - 1));
	// Neighbour offsets (di, dj, dk) and their group, in creation order.
	static const int offsets[13][4] = {
	    {0, 1, 0, 0}, {1, 0, 0, 0},  {0, 0, 1, 0},                                                // edges
	    {1, 1, 0, 1}, {1, -1, 0, 1}, {0, 1, 1, 1},  {0, -1, 1, 1},  {1, 0, 1, 1}, {-1, 0, 1, 1},  // faces
	    {1, 1, 1, 2}, {1, -1, 1, 2}, {-1, 1, 1, 2}, {-1, -1, 1, 2},                               // bodies
	};
	const sm_spring_material* groups[3] = {&def->edge, &def->face_diagonal, &def->body_diagonal};
	static const char* const group_names[3] = {"edge", "face diagonal", "body diagonal"};
	int32_t made[3] = {0, 0, 0};
	for (int64_t k = 0; k < nw && st == SM_OK; k++)
		for (int64_t i = 0; i < nv && st == SM_OK; i++)
			for (int64_t j = 0; j < nu && st == SM_OK; j++)
				for (int o = 0; o < 13 && st == SM_OK; o++) {
					const int g = offsets[o][3];
					const int64_t bi = i + offsets[o][0], bj = j + offsets[o][1], bk = k + offsets[o][2];
					if (!has[g] || bi < 0 || bi >= nv || bj < 0 || bj >= nu || bk >= nw)
						continue;
					const int64_t at[3] = {i, j, k};
					st = sm_structure_add_spring(
					    model, what, "size, nu, nv and nw", group_names[g],
					    p0 + (int32_t)((k * nv + i) * nu + j), p0 + (int32_t)((bk * nv + bi) * nu + bj),
					    groups[g], cell_volume * boundary_share(offsets[o], at, block_counts, 3));
					made[g]++;
				}
	if (st != SM_OK) {
		sm_structure_truncate(model, p0, s0);
		return st;
	}
	sm_structure_fill_out(out, p0, s0, model, def->nu, def->nv, def->nw, made);
	return SM_OK;
}

// ---------------------------------------------------------------------------------------------
// Selection.
// ---------------------------------------------------------------------------------------------

sm_status sm_set_motion_in_box(sm_model* model, const double lo[3], const double hi[3],
                               sm_particle_motion motion, int32_t* count)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (lo == NULL || hi == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "box selection: corner is NULL");
	for (int c = 0; c < 3; c++)
		if (isnan(lo[c]) || isnan(hi[c]))
			return sm_model_fail(model, SM_ERROR_NOT_FINITE, "box selection: corner coordinate %d is NaN", c);
	if (motion != SM_PARTICLE_FREE && motion != SM_PARTICLE_FIXED && motion != SM_PARTICLE_DRIVEN)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "box selection: motion = %d is not known",
		                     (int)motion);
	bool* inside = malloc((size_t)model->particle_count + 1);
	if (inside == NULL)
		return sm_model_fail(model, SM_ERROR_OUT_OF_MEMORY, "box selection: out of memory");
	int32_t changed = 0;
	for (int32_t p = 0; p < model->particle_count; p++) {
		const double* x = model->position + 3 * (size_t)p;
		inside[p] = x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1] && x[2] >= lo[2] &&
		            x[2] <= hi[2];
		changed += inside[p];
	}
	sm_model_set_motions(model, inside, NULL, 0, motion);
	free(inside);
	if (count != NULL)
		*count = changed;
	model->last_error[0] = '\0';
	return SM_OK;
}

sm_status sm_set_motion_at(sm_model* model, const sm_structure* structure, int32_t i, int32_t j, int32_t k,
                           sm_particle_motion motion)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (structure == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "selection: no structure given");
	const int32_t p = sm_structure_particle(structure, i, j, k);
	if (p < 0)
		return sm_model_fail(model, SM_ERROR_PARTICLE_INDEX,
		                     "grid coordinate (%d, %d, %d) is outside the structure", (int)i, (int)j, (int)k);
	// A structure built in another, larger model may name a particle this one does not have.
	if (p >= model->particle_count)
		return sm_model_fail(model, SM_ERROR_PARTICLE_INDEX,
		                     "grid coordinate (%d, %d, %d) is particle %d of the structure, beyond the "
		                     "model's %d particles: the structure belongs to another model",
		                     (int)i, (int)j, (int)k, (int)p, (int)model->particle_count);
	return sm_model_set_particle_motion(model, p, motion);
}

sm_status sm_set_motion_of(sm_model* model, const int32_t* particles, int32_t count,
                           sm_particle_motion motion)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (count < 0)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "selection: a count of %d particles",
		                     (int)count);
	if (count > 0 && particles == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "selection: %d particles given without a list",
		                     (int)count);
	if (motion != SM_PARTICLE_FREE && motion != SM_PARTICLE_FIXED && motion != SM_PARTICLE_DRIVEN)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "selection: motion = %d is not known",
		                     (int)motion);
	for (int32_t n = 0; n < count; n++)
		if (particles[n] < 0 || particles[n] >= model->particle_count)
			return sm_model_fail(
			    model, SM_ERROR_PARTICLE_INDEX,
			    "selection: entry %d, particle %d, is out of range (model has %d particle%s)", (int)n,
			    (int)particles[n], (int)model->particle_count, model->particle_count == 1 ? "" : "s");
	sm_model_set_motions(model, NULL, particles, count, motion);
	model->last_error[0] = '\0';
	return SM_OK;
}

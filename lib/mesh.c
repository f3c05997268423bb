// Triangle meshes: a spring on every edge, a bending spring across every interior edge, masses
// lumped from the triangles' areas.
//
// Lumped mass: a triangle of area A = |(x1 - x0) x (x2 - x0)| / 2 and areal density rho has
// mass rho A; each of its three vertices takes a third, so the total mass is rho times the
// mesh's area exactly, and a uniformly refined mesh keeps the same mass distribution.
//
// Edges are found in a hash table keyed by the sorted vertex pair (mesh_edges.h); each entry
// remembers how many triangles share the edge and the vertex opposite it in the first two, which
// are the ends of the bending spring across an interior edge.
#include "mesh_edges.h"
#include "structures_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

sm_mesh_def sm_default_mesh_def(void)
{
	sm_mesh_def d;
	memset(&d, 0, sizeof d);
	d.density = 1.0;
	d.edge = sm_default_spring_material();
	d.edge.stiffness = 1000.0;
	d.bend = sm_default_spring_material();
	return d;
}

// The checks on a definition's values; *triangle or *vertex names the one a failure is about.
static sm_status check_mesh(sm_model* model, const sm_mesh_def* def, int32_t* triangle, int32_t* vertex)
{
	static const char what[] = "mesh";
	sm_status st;
	if ((st = sm_structure_check_material(model, what, "edge", &def->edge, true)) != SM_OK ||
	    (st = sm_structure_check_material(model, what, "bend", &def->bend, true)) != SM_OK)
		return st;
	if (!isfinite(def->density) || !(def->density > 0.0))
		return sm_model_fail(model, isfinite(def->density) ? SM_ERROR_NONPOSITIVE_MASS : SM_ERROR_NOT_FINITE,
		                     "mesh: density = %g must be finite and > 0", def->density);
	if (def->vertex_count < 3 || def->triangle_count < 1) {
		// Too few vertices for a triangle: the first one has to repeat a vertex or name one that
		// is not there, and is the one this is about.
		if (def->triangle_count >= 1)
			*triangle = 0;
		return sm_model_fail(
		    model, SM_ERROR_INVALID_ARGUMENT,
		    "mesh: %d vert%s and %d triangle%s; a mesh needs at least 3 vertices and 1 triangle",
		    (int)def->vertex_count, def->vertex_count == 1 ? "ex" : "ices", (int)def->triangle_count,
		    def->triangle_count == 1 ? "" : "s");
	}
	if (def->vertices == NULL || def->triangles == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "mesh: vertex or triangle array is NULL");
	if (def->triangle_count > SM_STRUCTURE_MAX_ELEMENTS / 3)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
		                     "mesh: %d triangles exceed the limit of %d per structure",
		                     (int)def->triangle_count, SM_STRUCTURE_MAX_ELEMENTS / 3);
	if (def->vertex_count > SM_STRUCTURE_MAX_ELEMENTS)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
		                     "mesh: %d vertices exceed the limit of %d particles per structure",
		                     (int)def->vertex_count, SM_STRUCTURE_MAX_ELEMENTS);
	for (int32_t v = 0; v < def->vertex_count; v++)
		for (int c = 0; c < 3; c++)
			if (!isfinite(def->vertices[3 * (size_t)v + c])) {
				*vertex = v;
				return sm_model_fail(model, SM_ERROR_NOT_FINITE,
				                     "mesh: vertex %d coordinate %d = %g is not finite", (int)v, c,
				                     def->vertices[3 * (size_t)v + c]);
			}
	for (int32_t t = 0; t < def->triangle_count; t++) {
		const int32_t* tri = def->triangles + 3 * (size_t)t;
		for (int c = 0; c < 3; c++)
			if (tri[c] < 0 || tri[c] >= def->vertex_count) {
				*triangle = t;
				return sm_model_fail(
				    model, SM_ERROR_PARTICLE_INDEX,
				    "mesh: triangle %d vertex %d = %d is out of range (mesh has %d vertices)", (int)t, c,
				    (int)tri[c], (int)def->vertex_count);
			}
		if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
			*triangle = t;
			return sm_model_fail(model, SM_ERROR_SELF_SPRING,
			                     "mesh: triangle %d (%d, %d, %d) repeats a vertex", (int)t, (int)tri[0],
			                     (int)tri[1], (int)tri[2]);
		}
	}
	return SM_OK;
}

static double triangle_area(const double* vertices, const int32_t* tri)
{
	const double* a = vertices + 3 * (size_t)tri[0];
	const double* b = vertices + 3 * (size_t)tri[1];
	const double* c = vertices + 3 * (size_t)tri[2];
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
	const double squared = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
	if ((squared >= DBL_MIN && isfinite(squared)) || (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0))
		return 0.5 * sqrt(squared);
	// |n|^2 underflowed (sides below about 1e-77 m; |n| itself is not 0, or the triangle flat) or
	// overflowed (sides above about 1e77 m, or n itself): the cross product of the edges divided by
	// their largest component, then scaled back by its square, which a triangle whose springs the
	// model can hold (sides from 1.5e-154 m to 1.3e154 m) keeps a normal double. Exactly 0 stays
	// 0; an edge that overflows (largest = inf) gives NaN, an area beyond the largest double inf:
	// overflows, which the caller names.
	double largest = 0.0;
	for (int c = 0; c < 3; c++)
		largest = fmax(largest, fmax(fabs(u[c]), fabs(w[c])));
	double us[3], ws[3];
	for (int c = 0; c < 3; c++) {
		us[c] = u[c] / largest;
		ws[c] = w[c] / largest;
	}
	const double ns[3] = {us[1] * ws[2] - us[2] * ws[1], us[2] * ws[0] - us[0] * ws[2],
	                      us[0] * ws[1] - us[1] * ws[0]};
	return 0.5 * sqrt(ns[0] * ns[0] + ns[1] * ns[1] + ns[2] * ns[2]) * largest * largest;
}

// The sine of a triangle's smallest angle [1]: 2A / (a b), with a and b its two longest sides,
// since 2A = a b sin C for the angle C between any two sides and the smallest angle lies between
// the two longest. Collinear vertices give 0, up to the rounding of the cross product, a few ulps
// of a b: vertices given in decimal ((0.1, 0.2, 0.3) and (0.3, 0.6, 0.9) with the origin) leave
// a computed area of 1e-17 of it, never exactly 0. The edges are divided by their largest
// component first, so that the rule does not depend on the unit of length (the longest scaled
// side is then between 1 and sqrt(3), the second at least half of it: no underflow). NaN if an
// edge overflows (vertices more than the largest double apart): then the other two edges are
// nearly opposite, and the triangle flat unless its area overflows.
static double smallest_angle_sine(const double* vertices, const int32_t* tri)
{
	double edge[3][3], largest = 0.0;
	for (int k = 0; k < 3; k++) {
		const double* from = vertices + 3 * (size_t)tri[k];
		const double* to = vertices + 3 * (size_t)tri[(k + 1) % 3];
		for (int c = 0; c < 3; c++) {
			edge[k][c] = to[c] - from[c];
			largest = fmax(largest, fabs(edge[k][c]));
		}
	}
	if (!isfinite(largest))
		return NAN;
	if (!(largest > 0.0))
		return 0.0;
	double length[3];
	for (int k = 0; k < 3; k++) {
		for (int c = 0; c < 3; c++)
			edge[k][c] /= largest;
		length[k] = sqrt(edge[k][0] * edge[k][0] + edge[k][1] * edge[k][1] + edge[k][2] * edge[k][2]);
	}
	const double* u = edge[0];
	const double* w = edge[2];
	const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
	int shortest = 0;
	for (int k = 1; k < 3; k++)
		if (length[k] < length[shortest])
			shortest = k;
	const double sides = length[(shortest + 1) % 3] * length[(shortest + 2) % 3];
	return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / sides;
}

sm_status sm_add_mesh(sm_model* model, const sm_mesh_def* def, sm_structure* out)
{
	int32_t triangle, vertex;
	return sm_add_mesh_located(model, def, out, &triangle, &vertex);
}

sm_status sm_add_mesh_located(sm_model* model, const sm_mesh_def* def, sm_structure* out, int32_t* triangle,
                              int32_t* vertex)
{
	static const char what[] = "mesh";
	*triangle = *vertex = -1;
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (def == NULL)
		return sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT, "mesh: definition is NULL");
	sm_status st = check_mesh(model, def, triangle, vertex);
	if (st != SM_OK)
		return st;

	const int32_t nv = def->vertex_count, nt = def->triangle_count;
	mesh_edges table;
	const bool room = sm_mesh_edges_init(&table);
	double* mass = calloc((size_t)nv, sizeof(double));
	if (!room || mass == NULL) {
		st = sm_model_fail(model, SM_ERROR_OUT_OF_MEMORY, "mesh: out of memory for %d vertices", (int)nv);
		goto done;
	}

	for (int32_t t = 0; t < nt && st == SM_OK; t++) {
		const int32_t* tri = def->triangles + 3 * (size_t)t;
		const double area = triangle_area(def->vertices, tri);
		// Overflow first: the vertices are finite, so a NaN area is an overflow too (inf - inf in
		// the cross product), not a zero area.
		if (!isfinite(area)) {
			st =
			    sm_model_fail(model, SM_ERROR_NOT_FINITE,
				              "mesh: the area of triangle %d (%d, %d, %d) overflows (its edges are too long)",
				              (int)t, (int)tri[0], (int)tri[1], (int)tri[2]);
			*triangle = t;
			break;
		}
		// Zero area: exactly, or to rounding (collinear vertices), by the rule a sheet's edges
		// follow: the sine of the smallest angle at most 1e-12 (NaN, an edge that overflows
		// while the area does not, is a flat triangle too).
		const double sine = smallest_angle_sine(def->vertices, tri);
		if (!(area > 0.0) && sine > 1e-12) {
			st = sm_model_fail(
			    model, SM_ERROR_INVALID_ARGUMENT,
			    "mesh: the area of triangle %d (%d, %d, %d) underflows to 0 (its edges are too short)",
			    (int)t, (int)tri[0], (int)tri[1], (int)tri[2]);
			*triangle = t;
			break;
		}
		if (!(area > 0.0) || !(sine > 1e-12)) {
			st = sm_model_fail(
			    model, SM_ERROR_INVALID_ARGUMENT,
			    "mesh: triangle %d (%d, %d, %d) has zero area (to rounding: twice its area is at most "
			    "1e-12 times the product of its two longest edges)",
			    (int)t, (int)tri[0], (int)tri[1], (int)tri[2]);
			*triangle = t;
			break;
		}
		for (int c = 0; c < 3; c++)
			mass[tri[c]] += def->density * area / 3.0;
		for (int c = 0; c < 3; c++) {
			const int32_t a = tri[c], b = tri[(c + 1) % 3], opposite = tri[(c + 2) % 3];
			mesh_edge* e = sm_mesh_edges_find(&table, a, b);
			if (e == NULL) {
				st = sm_model_fail(model, SM_ERROR_OUT_OF_MEMORY,
				                   "mesh: out of memory for the edges of %d triangles", (int)nt);
				break;
			}
			if (e->triangles >= 2) {
				st = sm_model_fail(model, SM_ERROR_INVALID_ARGUMENT,
				                   "mesh: edge (%d, %d) of triangle %d is shared by more than two triangles",
				                   (int)a, (int)b, (int)t);
				break;
			}
			if (e->triangles == 1 && e->opposite[0] == opposite) {
				st = sm_model_fail(
				    model, SM_ERROR_INVALID_ARGUMENT,
				    "mesh: triangle %d repeats the vertices of an earlier triangle (%d, %d, %d)", (int)t,
				    (int)tri[0], (int)tri[1], (int)tri[2]);
				break;
			}
			e->opposite[e->triangles++] = opposite;
			e->area += area;
		}
		if (st != SM_OK && st != SM_ERROR_OUT_OF_MEMORY)
			*triangle = t;
	}
	for (int32_t v = 0; v < nv && st == SM_OK; v++) {
		if (mass[v] > 0.0 && isfinite(mass[v]))
			continue;
		*vertex = v;
		bool in_triangle = false;
		for (size_t k = 0; k < 3 * (size_t)nt && !in_triangle; k++)
			in_triangle = def->triangles[k] == v;
		if (!in_triangle)
			st = sm_model_fail(model, SM_ERROR_NONPOSITIVE_MASS, "mesh: vertex %d belongs to no triangle",
			                   (int)v);
		else if (mass[v] > 0.0)
			st = sm_model_fail(
			    model, SM_ERROR_NOT_FINITE,
			    "mesh: vertex %d: its mass, density %g kg/m^2 x a third of its triangles' area, is "
			    "beyond the largest double",
			    (int)v, def->density);
		else
			st = sm_model_fail(
			    model, SM_ERROR_NONPOSITIVE_MASS,
			    "mesh: vertex %d: its mass, density x a third of its triangles' area, is %g (must be "
			    "finite and > 0)",
			    (int)v, mass[v]);
	}
	if (st != SM_OK)
		goto done;

	const bool has_edge = sm_structure_material_present(&def->edge),
	           has_bend = sm_structure_material_present(&def->bend);
	int64_t interior = 0;
	for (int32_t e = 0; e < table.count; e++) {
		const mesh_edge* entry = sm_mesh_edges_at(&table, e);
		if (entry->triangles != 2)
			continue;
		interior++;
		// Two triangles folded onto each other about their edge: the vertices opposite it are
		// distinct but coincide, and the bend spring between them would have no length (as a
		// sheet's coincident grid neighbours, refused whatever its constants).
		const double* x = def->vertices + 3 * (size_t)entry->opposite[0];
		const double* y = def->vertices + 3 * (size_t)entry->opposite[1];
		if (has_bend && x[0] == y[0] && x[1] == y[1] && x[2] == y[2]) {
			st = sm_model_fail(
			    model, SM_ERROR_INVALID_ARGUMENT,
			    "mesh: the vertices %d and %d opposite edge (%d, %d) coincide at (%g, %g, %g) m (its two "
			    "triangles lie on each other): the bend spring across it would have no length",
			    (int)entry->opposite[0], (int)entry->opposite[1], (int)(entry->key >> 32),
			    (int)(entry->key & 0xffffffffu), x[0], x[1], x[2]);
			goto done;
		}
	}
	const int64_t springs = (has_edge ? table.count : 0) + (has_bend ? interior : 0);
	if ((st = sm_structure_check_size(model, what, nv, springs)) != SM_OK)
		goto done;

	const int32_t p0 = model->particle_count, s0 = model->spring_count;
	for (int32_t v = 0; v < nv && st == SM_OK; v++)
		st = sm_structure_add_particle(model, what, mass[v], def->vertices + 3 * (size_t)v);
	for (int32_t e = 0; e < table.count && st == SM_OK && has_edge; e++) {
		const mesh_edge* entry = sm_mesh_edges_at(&table, e);
		st = sm_structure_add_spring(model, what, "the vertices", "edge", p0 + (int32_t)(entry->key >> 32),
		                             p0 + (int32_t)(entry->key & 0xffffffffu), &def->edge, entry->area);
	}
	for (int32_t e = 0; e < table.count && st == SM_OK && has_bend; e++) {
		const mesh_edge* entry = sm_mesh_edges_at(&table, e);
		if (entry->triangles == 2)
			st = sm_structure_add_spring(model, what, "the vertices", "bend", p0 + entry->opposite[0],
			                             p0 + entry->opposite[1], &def->bend, entry->area);
	}
	if (st != SM_OK) {
		sm_structure_truncate(model, p0, s0);
		goto done;
	}
	const int32_t made[3] = {has_edge ? table.count : 0, has_bend ? (int32_t)interior : 0, 0};
	sm_structure_fill_out(out, p0, s0, model, nv, 1, 1, made);
done:
	sm_mesh_edges_free(&table);
	free(mass);
	return st;
}

// springmass: structures built from particles and springs (ropes, sheets, blocks, triangle
// meshes) and helpers to select their particles.
//
// Each builder appends particles and springs to a model and reports the index ranges it
// created in an sm_structure, so callers can fix, drive or probe particles of the structure.
// On error the model's particles and springs are left exactly as they were (nothing half-built;
// only the room reserved for them may have grown) and sm_model_last_error() names the field and
// the rule it broke. Sizes: every spring a builder makes must be between sqrt(DBL_MIN) = 1.5e-154
// and sqrt(DBL_MAX) = 1.3e154 m long (lengths are computed from their squares), per-section
// sections finite and > 0, and every position a finite double; otherwise the builder fails
// (SM_ERROR_INVALID_ARGUMENT for too small, SM_ERROR_NOT_FINITE for too large) naming the spring
// and the fields that set its size.
#pragma once

#include "springmass/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Largest number of particles, and of springs, one builder call may create (a mesh: at most a
/// third of it in triangles), and a builder refuses to grow the model past 4 times it in all.
/// Larger requests fail with SM_ERROR_INVALID_ARGUMENT before anything is allocated.
#define SM_STRUCTURE_MAX_ELEMENTS (1 << 24)

/// Constants of one group of springs (structural, shear, bend, ...). A group whose stiffness
/// and damping are both zero is not created, unless keep_when_zero is set.
///
/// Per section (SM_PER_SECTION; sheets, blocks and meshes, not ropes), each spring stands for a
/// share of the structure's area (sheet, mesh) or volume (block), and its section is that share
/// over its length: a sheet's or block's grid cell, halved for each boundary line or face the
/// spring runs along; the triangles on both sides of a mesh edge (for its edge spring and the
/// bend spring across it). Then the springs of one direction, stretched uniformly along it,
/// carry stiffness x strain per unit width of a sheet [N/m] or per unit area of a block's
/// cross-section [N/m^2] across them, whatever the grid: the lattice's elastic constants depend
/// on the shape of its cells, not on their number (but for a sheet's bend group, whose springs
/// span two cells and so leave the last cell of each row and column without one: its modulus is
/// (nu - 2)/(nu - 1) of the value along u when every particle moves with the stretch, 0.75 at 5
/// particles, and less where the particles next to the edges settle, all four edges held; both
/// tend to the value as the grid is refined; docs/model-format.md gives figures). A mesh's edge
/// springs per section give an equilateral triangulation a membrane Young's modulus of
/// `stiffness` [N/m] (Poisson's ratio 1/3); other triangle shapes other constants.
///
/// Per strain, a rope's structural springs are in series, so its stretch under a load does not
/// depend on its segments; its bending springs (p, p + 2) are not: two of them cross every
/// segment but the first and the last, so they add twice their value to the rope's axial
/// stiffness inside and once across its end segments (docs/model-format.md, Rope).
typedef struct sm_spring_material {
	double stiffness;              ///< ks [N/m]; per strain, E [N]; per section, [N/m] or [N/m^2]; default 0
	sm_scaling stiffness_scaling;  ///< default SM_PER_STRAIN
	double damping;  ///< kd [N s/m]; per strain, c [N s]; per section, [N s/m] or [N s/m^2]; default 0
	sm_scaling damping_scaling;  ///< default SM_PER_STRAIN
	double break_strain;         ///< [1], > SM_MIN_BREAK_STRAIN; INFINITY (default) = never breaks
	/// Create the group's springs even when stiffness and damping are both zero (default false),
	/// so that the model keeps its topology when they are given values later (through
	/// sm_simulation_update_model, or a model file's parameters: see docs/model-format.md).
	bool keep_when_zero;
} sm_spring_material;

/// How a rope, sheet or block spreads its mass over its particles.
typedef enum sm_mass_distribution {
	/// Every particle the same share (default; the benchmark cloth's).
	SM_MASS_EVEN = 0,
	/// Each particle the share of the length, area or volume nearest to it: a half at a rope's
	/// end or a sheet's or block's boundary, a quarter at a corner of a sheet (and where two of a
	/// block's faces meet), an eighth at a block's corner, the lumped masses of the grid's cells.
	/// With per-section constants a refined structure then keeps its masses where its springs
	/// are, and its results converge faster (docs/model-format.md).
	SM_MASS_LUMPED,
} sm_mass_distribution;

/// Index ranges created by a builder, and the grid shape for grid addressing.
typedef struct sm_structure {
	int32_t first_particle;  ///< index of the structure's first particle
	int32_t particle_count;  ///< its particles are first_particle .. first_particle + particle_count - 1
	int32_t first_spring;    ///< its springs are first_spring .. first_spring + spring_count - 1
	int32_t spring_count;
	int32_t shape[3];  ///< grid points per axis (rope: segments + 1, 1, 1; mesh: vertices, 1, 1)
	/// Springs made of each group, in the order of the definition's materials: rope structural,
	/// bending; sheet structural, shear, bend; block edge, face_diagonal, body_diagonal; mesh
	/// edge, bend (a mesh's edge springs come first: springs first_spring ..
	/// first_spring + group_spring_count[0] - 1). Entries past the groups are 0.
	int32_t group_spring_count[3];
} sm_structure;

/// Index of the particle at grid coordinate (i, j, k) of a structure, or -1 if outside the grid.
/// Column j runs along the first axis (shape[0] points), row i along the second (shape[1]),
/// layer k along the third (shape[2]): index first_particle + (k * shape[1] + i) * shape[0] + j.
/// For a rope or a mesh (one row), use i = k = 0 and j = the point's position along the rope or
/// the vertex index.
SM_API int32_t sm_structure_particle(const sm_structure* structure, int32_t i, int32_t j, int32_t k);

/// Zero constants (no springs), per-strain scaling, never breaks.
SM_API sm_spring_material sm_default_spring_material(void);

/// Rope or chain: a straight polyline of `segments` springs from start to end. Particle p
/// (0 <= p <= segments) sits at start + p / segments (end - start), the last exactly at end, and
/// has index first_particle + p. Springs, in order: for each p, the structural spring (p, p + 1),
/// then the bending spring (p, p + 2) where it exists.
/// start = end is allowed with absolute constants (springs of rest length 0, which pull like
/// zero-length springs); per-strain constants, a finite break strain and mass_per_length need a
/// length: SM_ERROR_ZERO_REST_LENGTH (mass_per_length: SM_ERROR_NONPOSITIVE_MASS). Ends that
/// differ but leave neighbouring particles at one point (a spacing below the rounding of the
/// coordinates) are refused (SM_ERROR_INVALID_ARGUMENT), as for a sheet's grid.
typedef struct sm_rope_def {
	double start[3];   ///< first particle's position [m]; default (0, 0, 0)
	double end[3];     ///< last particle's position [m]; default (1, 0, 0)
	int32_t segments;  ///< number of structural springs, >= 1; default 10
	double mass;       ///< total mass [kg] > 0 over the segments + 1 particles; default 1
	/// [kg/m]; > 0 overrides mass (total = mass_per_length |end - start|); default 0
	double mass_per_length;
	sm_mass_distribution mass_distribution;  ///< default SM_MASS_EVEN
	sm_spring_material structural;  ///< springs between neighbours; default E = 1000 N per strain, no damping
	sm_spring_material bending;     ///< springs to the second neighbour; zero constants (default) = none
} sm_rope_def;

/// Sheet (cloth): nu x nv particles on the parallelogram origin + s edge_u + t edge_v,
/// s, t in [0, 1]. Particle (i, j) sits at origin + j/(nu-1) edge_u + i/(nv-1) edge_v and has
/// index i * nu + j. For each particle in index order, springs to (i, j+1), (i+1, j) [structural],
/// (i+1, j+1), (i+1, j-1) [shear], (i, j+2), (i+2, j) [bend], where they exist and their group
/// has constants: the same particles and springs, in the same order, as the benchmark cloth.
/// The default definition is the benchmark cloth with n = 16 (1 m x 1 m in the z = 0 plane,
/// 1 kg, E = 1000 N structural and shear, 50 N bend, c = 2 N s for all, per strain).
typedef struct sm_sheet_def {
	double origin[3];                        ///< [m]; default (0, 0, 0)
	double edge_u[3];                        ///< first edge [m]; default (1, 0, 0)
	double edge_v[3];                        ///< second edge [m]; default (0, 1, 0)
	int32_t nu;                              ///< particles along edge_u, >= 2; default 16
	int32_t nv;                              ///< particles along edge_v, >= 2; default 16
	double mass;                             ///< total mass [kg] > 0; default 1
	sm_mass_distribution mass_distribution;  ///< default SM_MASS_EVEN
	sm_spring_material structural;
	sm_spring_material shear;
	sm_spring_material bend;
} sm_sheet_def;

/// Block (jelly cube): nu x nv x nw lattice in the box origin + [0,1]^3 spanned by size[3],
/// with edge springs (lattice neighbours), face-diagonal springs (both diagonals of every
/// lattice square face) and body-diagonal springs (all four diagonals of every cell), so it
/// resists shear in every direction. Particle (i, j, k) at origin + (j/(nu-1) size[0],
/// i/(nv-1) size[1], k/(nw-1) size[2]) has index (k * nv + i) * nu + j. For each particle in
/// index order, springs to the neighbours (i, j+1, k), (i+1, j, k), (i, j, k+1) [edge],
/// (i+1, j+1, k), (i+1, j-1, k), (i, j+1, k+1), (i, j-1, k+1), (i+1, j, k+1), (i-1, j, k+1)
/// [face diagonal], (i+1, j+1, k+1), (i+1, j-1, k+1), (i-1, j+1, k+1), (i-1, j-1, k+1)
/// [body diagonal], where they exist and their group has constants.
/// The default is a 1 m cube of 4 x 4 x 4 particles, 1 kg, E = 1000 N in every group.
typedef struct sm_block_def {
	double origin[3];                        ///< [m]; default (0, 0, 0)
	double size[3];                          ///< edge lengths along x, y, z [m], > 0; default (1, 1, 1)
	int32_t nu, nv, nw;                      ///< particles along x, y, z, each >= 2; default 4
	double mass;                             ///< total mass [kg] > 0; default 1
	sm_mass_distribution mass_distribution;  ///< default SM_MASS_EVEN
	sm_spring_material edge;
	sm_spring_material face_diagonal;
	sm_spring_material body_diagonal;
} sm_block_def;

/// Triangle mesh: a spring on every edge (each edge once, in order of first appearance, edges
/// of a triangle (v0, v1), (v1, v2), (v2, v0), each spring from the lower vertex index to the
/// higher) and then a bending spring across every interior
/// edge (between the two vertices opposite it, in the order of the edges). Each vertex gets a
/// third of the mass of every triangle it belongs to, the triangle's mass being its area times
/// the density; vertex v becomes particle first_particle + v.
/// Errors: a vertex index out of range, a triangle with a repeated vertex or zero area (to
/// rounding: twice its area at most 1e-12 times the product of its two longest edges, the sine
/// of its smallest angle, as for collinear vertices given in decimal), an edge
/// shared by more than two triangles, two triangles on the same three vertices, a vertex that
/// belongs to no triangle (it would have no mass), and with bend springs two triangles folded
/// onto each other (the vertices opposite their common edge at the same position).
typedef struct sm_mesh_def {
	const double* vertices;  ///< 3 per vertex [m]; not copied, read during the call only
	int32_t vertex_count;
	const int32_t* triangles;  ///< 3 vertex indices per triangle
	int32_t triangle_count;
	double density;           ///< areal density [kg/m^2], > 0; default 1
	sm_spring_material edge;  ///< default E = 1000 N per strain, no damping
	sm_spring_material bend;  ///< default none (zero constants)
} sm_mesh_def;

/// Definitions with the defaults documented in their structs.
SM_API sm_rope_def sm_default_rope_def(void);
SM_API sm_sheet_def sm_default_sheet_def(void);
SM_API sm_block_def sm_default_block_def(void);
SM_API sm_mesh_def sm_default_mesh_def(void);

/// Builders: append the structure to the model and describe it in *out (may be NULL). On error
/// the model is unchanged and sm_model_last_error() names the field and the rule.
SM_API sm_status sm_add_rope(sm_model* model, const sm_rope_def* def, sm_structure* out);
SM_API sm_status sm_add_sheet(sm_model* model, const sm_sheet_def* def, sm_structure* out);
SM_API sm_status sm_add_block(sm_model* model, const sm_block_def* def, sm_structure* out);
SM_API sm_status sm_add_mesh(sm_model* model, const sm_mesh_def* def, sm_structure* out);

/// Sets the motion of every particle whose initial position lies in the closed box [lo, hi]
/// [m]; writes how many particles lie in the box to *count (may be NULL), those that had that
/// motion already included. An empty box is not an error.
SM_API sm_status sm_set_motion_in_box(sm_model* model, const double lo[3], const double hi[3],
                                      sm_particle_motion motion, int32_t* count);

/// Sets the motion of the particle at grid coordinate (i, j, k) of a structure (see
/// sm_structure_particle); SM_ERROR_PARTICLE_INDEX if the coordinate is outside the grid.
SM_API sm_status sm_set_motion_at(sm_model* model, const sm_structure* structure, int32_t i, int32_t j,
                                  int32_t k, sm_particle_motion motion);

/// Sets the motion of `count` particles given by index; all indices are checked first, so on
/// error nothing changed.
SM_API sm_status sm_set_motion_of(sm_model* model, const int32_t* particles, int32_t count,
                                  sm_particle_motion motion);

#ifdef __cplusplus
}
#endif

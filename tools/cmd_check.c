// springmass check: validates a model file and prints a summary of what it builds.
#include "cli_common.h"
#include "commands.h"

#include "springmass/analysis.h"
#include "springmass/model_file.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE* out)
{
	fprintf(out,
	        "usage: springmass check MODEL [--set NAME=VALUE ...]\n"
	        "\n"
	        "Validates the model file MODEL (JSON, see docs/model-format.md) and prints a summary:\n"
	        "particles (free, fixed), springs by kind, total mass, ports, parameters (with what each\n"
	        "feeds: constants, initial state, held particles, counts, settings, spring kinds,\n"
	        "particle references), the stiffest spring, the fastest spring (the largest sqrt(k/m),\n"
	        "with m the lighter of its free ends) and an upper bound on the highest natural frequency\n"
	        "omega_max (Gershgorin's over the springs' stiffness, undamped) and, with the same bound on\n"
	        "the modes' damping rates, a step at which explicit (symplectic Euler) integration is\n"
	        "stable; `springmass modes MODEL -n 0` gives a closer value from every mode's own\n"
	        "frequency and damping rate. Warnings: absolute tolerances coarse for the model's scales, a\n"
	        "velocity tolerance too tight for the round-off of a stiff spring's force, two vertices of\n"
	        "a mesh at the same position (no spring joins them: the mesh is cut there), springs that\n"
	        "start at or beyond their break strain (they break at t = 0), accelerations or a\n"
	        "dissipated power that overflow at the initial state (a run stops at t = 0). Notes:\n"
	        "springs of the file's \"springs\" that join the same two particles as another spring (their\n"
	        "forces add: a spring listed twice?).\n"
	        "\n"
	        "  --set NAME=VALUE   a parameter's value (repeatable), checked as a whole with the others\n"
	        "  -h, --help         this text\n"
	        "\n"
	        "Exit status: 0 if the file is valid, 1 if not (the error names the line and column or the\n"
	        "element of the file and the rule it breaks), 2 on a usage error.\n");
}

static const char* port_kind(sm_port_kind kind)
{
	return kind == SM_PORT_FORCE ? "force" : kind == SM_PORT_MOTION ? "motion" : "probe";
}

static void print_particle(const sm_document* doc, int32_t particle)
{
	const char* name = sm_document_particle_name(doc, particle);
	if (name != NULL) {
		cli_write_text(stdout, name, 0);
		printf(" (particle %d)", (int)particle);
	} else
		printf("particle %d", (int)particle);
}

// Most springs that start beyond their break strain named one by one; the rest are counted.
#define BROKEN_AT_START_SHOWN 3

// Warns about the springs whose initial strain is at or beyond their break strain: they break at
// once, as the first advance starts (at t = 0), and only the rows written before it show them
// (the first of `springmass run`'s CSV). Most likely a rest length shorter than meant, or a break
// strain below the strain of a spring pre-stretched on purpose. The test is the simulation's, on
// lengths: L >= l0 (1 + break strain) (a strain (L - l0) / l0 can round below a limit that L
// reaches). False when out of memory.
static bool warn_broken_at_start(const sm_document* doc, const sm_model* model)
{
	const int32_t n = sm_model_particle_count(model), m = sm_model_spring_count(model);
	double* x = malloc((3 * (size_t)n + 1) * sizeof(double));
	double* length = malloc(2 * ((size_t)m + 1) * sizeof(double));
	if (x == NULL || length == NULL) {
		free(x);
		free(length);
		return false;
	}
	double* strain = length + m + 1;
	sm_model_initial_state(model, x, NULL);
	sm_model_spring_states(model, x, NULL, length, strain, NULL);
	int32_t count = 0;
	for (int32_t k = 0; k < m; k++) {
		sm_spring_def s;
		double l0 = 0.0;
		sm_model_get_spring(model, k, &s);
		sm_model_spring_constants(model, k, &l0, NULL, NULL);
		if (!sm_model_spring_enabled(model, k) || !isfinite(s.break_strain) ||
		    !(length[k] >= l0 * (1.0 + s.break_strain)))
			continue;
		if (++count > BROKEN_AT_START_SHOWN)
			continue;
		printf("warning      spring %d, between ", (int)k);
		print_particle(doc, s.a);
		printf(" and ");
		print_particle(doc, s.b);
		printf(", starts at strain %.6g, at or beyond its break strain %.6g: it breaks at t = 0\n", strain[k],
		       s.break_strain);
	}
	if (count == BROKEN_AT_START_SHOWN + 1)
		printf("warning      and 1 more spring starts at or beyond its break strain\n");
	else if (count > BROKEN_AT_START_SHOWN)
		printf("warning      and %d more springs start at or beyond their break strain\n",
		       (int)(count - BROKEN_AT_START_SHOWN));
	free(x);
	free(length);
	return true;
}

// Most pairs of springs that join the same two particles named one by one; the rest are counted.
#define PARALLEL_SHOWN 3

// Two particles, the lower index first.
typedef struct particle_pair {
	int32_t a, b;
} particle_pair;

static int by_particles(const void* a, const void* b)
{
	const particle_pair *p = a, *q = b;
	return p->a != q->a ? (p->a > q->a) - (p->a < q->a) : (p->b > q->b) - (p->b < q->b);
}

// A spring and the particles it joins, for sorting by them.
typedef struct joined_pair {
	particle_pair ends;
	int32_t spring;
	int32_t structure;  // the structure that made it, or -1 for the file's "springs"
} joined_pair;

static int by_joined_pair(const void* a, const void* b)
{
	const joined_pair *p = a, *q = b;
	const int ends = by_particles(&p->ends, &q->ends);
	return ends != 0 ? ends : (p->spring > q->spring) - (p->spring < q->spring);
}

// Notes the springs of the file's "springs" that join the same two particles as an earlier spring:
// one listed twice, or one that a structure already has. Legitimate physics (parallel springs add
// their forces; a spring beside a damper of its own), but more often a slip that makes the pair
// twice as stiff as meant. A structure's own springs on one pair are its design (a mesh's bending
// springs across two edges with the same opposite vertices) and are not noted. Each spring noted is
// paired with the first spring on its particles. False when out of memory.
static bool note_parallel_springs(const sm_document* doc, const sm_model* model)
{
	const int32_t m = sm_model_spring_count(model);
	joined_pair* pairs = malloc(((size_t)m + 1) * sizeof *pairs);
	if (pairs == NULL)
		return false;
	for (int32_t k = 0; k < m; k++) {
		sm_spring_def s;
		sm_model_get_spring(model, k, &s);
		pairs[k] = (joined_pair){{s.a < s.b ? s.a : s.b, s.a < s.b ? s.b : s.a}, k, -1};
	}
	for (int32_t j = 0; j < sm_document_structure_count(doc); j++) {
		const sm_structure r = sm_document_structure(doc, j).range;
		for (int32_t k = r.first_spring; k < r.first_spring + r.spring_count; k++)
			pairs[k].structure = j;
	}
	qsort(pairs, (size_t)m, sizeof *pairs, by_joined_pair);
	int32_t count = 0;
	for (int32_t k = 1, first = 0; k < m; k++) {
		if (by_particles(&pairs[k].ends, &pairs[first].ends) != 0) {
			first = k;
			continue;
		}
		if (pairs[k].structure >= 0 && pairs[k].structure == pairs[first].structure)
			continue;
		if (++count > PARALLEL_SHOWN)
			continue;
		printf("note         springs %d and %d both join ", (int)pairs[first].spring, (int)pairs[k].spring);
		print_particle(doc, pairs[k].ends.a);
		printf(" and ");
		print_particle(doc, pairs[k].ends.b);
		printf(": they act in parallel, their forces add (a spring listed twice?)\n");
	}
	if (count > PARALLEL_SHOWN)
		printf("note         and %d more spring%s join%s the same particles as an earlier one\n",
		       (int)(count - PARALLEL_SHOWN), count - PARALLEL_SHOWN > 1 ? "s" : "",
		       count - PARALLEL_SHOWN > 1 ? "" : "s");
	free(pairs);
	return true;
}

// A model can obey every rule of the file and still have forces or accelerations that overflow
// a double at its initial state (a weight beyond 1.8e308 N, a force over a tiny mass): `springmass
// run` then stops at its first evaluation, at t = 0. The test is the simulation's: every free
// particle's acceleration f / m [m/s^2] finite, and the dissipated power [W]. The first such
// particle is named and the others counted. *overflows tells whether it warned. False when out of
// memory.
static bool warn_overflow_at_start(const sm_document* doc, const sm_model* model, bool* overflows)
{
	const int32_t n = sm_model_particle_count(model);
	double* x = malloc((9 * (size_t)n + 1) * sizeof(double));
	if (x == NULL)
		return false;
	double *v = x + 3 * (size_t)n, *f = v + 3 * (size_t)n;
	sm_model_initial_state(model, x, v);
	sm_model_forces(model, x, v, NULL, f);
	int32_t count = 0, first = -1;
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		if (p.motion != SM_PARTICLE_FREE)
			continue;
		const double* fi = f + 3 * (size_t)i;
		if (isfinite(fi[0] / p.mass) && isfinite(fi[1] / p.mass) && isfinite(fi[2] / p.mass))
			continue;
		if (count++ == 0)
			first = i;
	}
	*overflows = count > 0;
	if (count > 0) {
		printf("warning      the acceleration of ");
		print_particle(doc, first);
		if (count > 1)
			printf(" (and of %d more free particle%s)", (int)(count - 1), count > 2 ? "s" : "");
		printf(" overflows at the initial state: springmass run stops at t = 0\n");
	} else if (!isfinite(sm_model_dissipated_power(model, x, v))) {
		*overflows = true;
		printf(
		    "warning      the dissipated power overflows at the initial state: springmass run stops at t = 0\n");
	}
	free(x);
	return true;
}

// A mesh's vertex where the model starts, for sorting by position.
typedef struct placed_vertex {
	double x[3];  // [m]
	int32_t particle;
} placed_vertex;

static int by_position(const void* a, const void* b)
{
	const placed_vertex *p = a, *q = b;
	for (int c = 0; c < 3; c++)
		if (p->x[c] != q->x[c])
			return p->x[c] < q->x[c] ? -1 : 1;
	return (p->particle > q->particle) - (p->particle < q->particle);
}

// Whether two points are the same, coordinate by coordinate.
static bool same_position(const double* a, const double* b)
{
	return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

// The vertex that stands for v's piece: the root of its tree in `piece` (mesh vertices from 0),
// each link on the way pointed at its grandparent.
static int32_t piece_of(int32_t* piece, int32_t v)
{
	while (piece[v] != v) {
		piece[v] = piece[piece[v]];
		v = piece[v];
	}
	return v;
}

// Most pairs of coinciding mesh vertices named one by one; the rest are counted.
#define COINCIDENT_SHOWN 3

// Warns about two vertices of one mesh that start at the same position, not both fixed, that no
// spring joins. The mesh makes none there (a triangle with both would have no area), so it is
// cut between them: most often a seam the modeller exported with its vertices duplicated (a UV
// seam, the ends of a strip wrapped into a tube, faces split apart), which comes apart as the
// model runs. Springs of the file's "springs" between vertices at the same position (zero-length
// ones stitching the seam) join them into one piece, directly or through others there (a pole
// whose copies are all stitched to one of them): two vertices of one piece are not warned of.
// Exact equality, as duplicated vertices are written with the same numbers. False when out of
// memory.
static bool warn_coincident_mesh_vertices(const sm_document* doc, const sm_model* model)
{
	const int32_t n = sm_model_particle_count(model), m = sm_model_spring_count(model);
	double* x = malloc((3 * (size_t)n + 1) * sizeof(double));
	placed_vertex* vertices = malloc(((size_t)n + 1) * sizeof *vertices);
	int32_t* piece = malloc(((size_t)n + 1) * sizeof *piece);
	particle_pair* pairs = malloc(((size_t)n + 1) * sizeof *pairs);
	bool ok = x != NULL && vertices != NULL && piece != NULL && pairs != NULL;
	if (ok)
		sm_model_initial_state(model, x, NULL);
	for (int32_t k = 0; ok && k < sm_document_structure_count(doc); k++) {
		const sm_structure_info s = sm_document_structure(doc, k);
		if (strcmp(s.type, "mesh") != 0)
			continue;
		const int32_t first = s.range.first_particle, count = s.range.particle_count;
		for (int32_t v = 0; v < count; v++) {
			memcpy(vertices[v].x, x + 3 * (size_t)(first + v), sizeof vertices[v].x);
			vertices[v].particle = first + v;
		}
		qsort(vertices, (size_t)count, sizeof *vertices, by_position);
		// Whether neighbours in that order start at the same position (most meshes: none).
		bool coinciding = false;
		for (int32_t v = 1; v < count && !coinciding; v++)
			coinciding = same_position(vertices[v - 1].x, vertices[v].x);
		if (!coinciding)
			continue;
		// The pieces the springs between vertices at the same position stitch the mesh's vertices
		// into.
		for (int32_t v = 0; v < count; v++)
			piece[v] = v;
		for (int32_t j = 0; j < m; j++) {
			sm_spring_def spring;
			sm_model_get_spring(model, j, &spring);
			const int32_t a = spring.a - first, b = spring.b - first;
			if (a >= 0 && a < count && b >= 0 && b < count &&
			    same_position(x + 3 * (size_t)spring.a, x + 3 * (size_t)spring.b))
				piece[piece_of(piece, a)] = piece_of(piece, b);
		}
		// Neighbours at the same position (a vertex repeated three times, two pairs), not both
		// fixed, in two pieces: named in the particles' order.
		int32_t cut = 0;
		for (int32_t v = 1; v < count; v++) {
			const placed_vertex *a = &vertices[v - 1], *b = &vertices[v];
			if (!same_position(a->x, b->x) ||
			    piece_of(piece, a->particle - first) == piece_of(piece, b->particle - first))
				continue;
			sm_particle_def pa, pb;
			sm_model_get_particle(model, a->particle, &pa);
			sm_model_get_particle(model, b->particle, &pb);
			if (pa.motion == SM_PARTICLE_FREE || pb.motion == SM_PARTICLE_FREE)
				pairs[cut++] = (particle_pair){a->particle, b->particle};
		}
		qsort(pairs, (size_t)cut, sizeof *pairs, by_particles);
		for (int32_t j = 0; j < cut && j < COINCIDENT_SHOWN; j++) {
			const double* at = x + 3 * (size_t)pairs[j].a;
			printf("warning      ");
			print_particle(doc, pairs[j].a);
			printf(" and ");
			print_particle(doc, pairs[j].b);
			printf(
			    " start at the same position, (%g, %g, %g) m, and no spring joins them: the mesh %s is cut "
			    "there (a seam of duplicated vertices? merge them in the modeller)\n",
			    at[0], at[1], at[2], s.name);
		}
		if (cut > COINCIDENT_SHOWN)
			printf("warning      and %d more pair%s of the mesh %s's vertices start at the same position\n",
			       (int)(cut - COINCIDENT_SHOWN), cut - COINCIDENT_SHOWN > 1 ? "s" : "", s.name);
	}
	free(x);
	free(vertices);
	free(piece);
	free(pairs);
	return ok;
}

// One line per structure: its kind and grid (and the OBJ file a mesh was read from, if any: `file`,
// or NULL), its particles and springs, and the springs of each of its groups (the groups of
// structures.h, in the order of their materials).
static void print_structure(const sm_structure_info* s, const char* file)
{
	static const char* const rope[] = {"structural", "bending", NULL};
	static const char* const sheet[] = {"structural", "shear", "bend"};
	static const char* const block[] = {"edge", "face diagonal", "body diagonal"};
	static const char* const mesh[] = {"edge", "bend", NULL};
	const char* const* groups = rope;
	const sm_structure* r = &s->range;
	printf("  %-12s %s ", s->name, s->type);
	if (strcmp(s->type, "rope") == 0) {
		printf("of %d segment%s", (int)r->shape[0] - 1, r->shape[0] == 2 ? "" : "s");
	} else if (strcmp(s->type, "sheet") == 0) {
		printf("%d x %d", (int)r->shape[0], (int)r->shape[1]);
		groups = sheet;
	} else if (strcmp(s->type, "block") == 0) {
		printf("%d x %d x %d", (int)r->shape[0], (int)r->shape[1], (int)r->shape[2]);
		groups = block;
	} else {
		printf("of %d vertices", (int)r->shape[0]);
		char* shown = file != NULL ? malloc(SM_TERMINAL_TEXT_CAPACITY(strlen(file))) : NULL;
		if (shown != NULL) {
			sm_text_for_terminal(shown, file);
			printf(" from %s", shown);
		}
		free(shown);
		groups = mesh;
	}
	printf(": particles %d - %d, %d spring%s", (int)r->first_particle,
	       (int)(r->first_particle + r->particle_count - 1), (int)r->spring_count,
	       r->spring_count == 1 ? "" : "s");
	const char* separator = " (";
	for (int g = 0; g < 3; g++)
		if (groups[g] != NULL && r->group_spring_count[g] > 0) {
			printf("%s%d %s", separator, (int)r->group_spring_count[g], groups[g]);
			separator = ", ";
		}
	printf("%s\n", separator[0] == ',' ? ")" : "");
}

int sm_cmd_check(int argc, char** argv)
{
	const char* path = NULL;
	const char** sets = calloc((size_t)argc + 1, sizeof *sets);
	int set_count = 0;
	if (sets == NULL)
		return 1;
	for (int i = 1; i < argc; i++) {
		if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
			usage(stdout);
			free(sets);
			return 0;
		}
		if (strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
			sets[set_count++] = argv[++i];
			continue;
		}
		if (cli_model_argument("check", argv[i], &path) != 0) {
			usage(stderr);
			free(sets);
			return 2;
		}
	}
	if (cli_model_given("check", path) != 0) {
		usage(stderr);
		free(sets);
		return 2;
	}

	sm_document* doc = NULL;
	sm_model* model = NULL;
	const int status = cli_load_model("check", path, sets, set_count, &doc, &model);
	free(sets);
	if (status != 0)
		return status;

	// The settings must also suit `springmass run MODEL`, which writes a row every interval.
	const sm_document_settings settings = sm_document_get_settings(doc);
	if (cli_output_rows(settings.stop_time, settings.output_interval) < 0) {
		char end[SM_NUMBER_TEXT_CAPACITY], step[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(settings.stop_time, end);
		sm_format_number(settings.output_interval, step);
		cli_shown shown = {0};
		fprintf(
		    stderr,
		    "springmass check: %s: simulation: stop_time / output_interval = %s s / %s s would make more than %g "
		    "output rows in springmass run\n",
		    cli_shown_path(&shown, path), end, step, CLI_MAX_ROWS);
		cli_shown_free(&shown);
		sm_model_destroy(model);
		sm_document_destroy(doc);
		return 1;
	}

	const int32_t n = sm_model_particle_count(model), m = sm_model_spring_count(model);
	// A model file's particles are free or fixed (an FMU drives its motion ports' particles).
	int32_t fixed = 0;
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		fixed += p.motion == SM_PARTICLE_FIXED;
	}
	int32_t rest_length = 0, zero_length = 0, per_strain = 0, per_section = 0, breakable = 0;
	int32_t stiffest = -1, fastest = -1;
	double max_stiffness = -1.0, max_omega = 0.0;
	for (int32_t s = 0; s < m; s++) {
		sm_spring_def def;
		double ks;
		sm_model_get_spring(model, s, &def);
		sm_model_spring_constants(model, s, NULL, &ks, NULL);
		if (def.kind == SM_SPRING_ZERO_LENGTH)
			zero_length++;
		else
			rest_length++;
		per_strain += def.stiffness_scaling == SM_PER_STRAIN;
		per_section += def.stiffness_scaling == SM_PER_SECTION;
		breakable += isfinite(def.break_strain);
		if (ks > max_stiffness) {
			max_stiffness = ks;
			stiffest = s;
		}
		// A spring's own frequency sqrt(ks / m) with m the lighter of its free ends (a fixed end
		// does not move): which spring makes the model fast.
		sm_particle_def pa, pb;
		sm_model_get_particle(model, def.a, &pa);
		sm_model_get_particle(model, def.b, &pb);
		double mass = INFINITY;
		if (pa.motion == SM_PARTICLE_FREE)
			mass = pa.mass;
		if (pb.motion == SM_PARTICLE_FREE)
			mass = fmin(mass, pb.mass);
		if (isfinite(mass) && sqrt(ks / mass) > max_omega) {
			max_omega = sqrt(ks / mass);
			fastest = s;
		}
	}

	printf("model        %s\n", sm_document_name(doc));
	if (sm_document_description(doc)[0] != '\0') {
		printf("description  ");
		cli_write_text(stdout, sm_document_description(doc), 0);
		printf("\n");
	}
	printf("particles    %d: %d free, %d fixed\n", (int)n, (int)(n - fixed), (int)fixed);
	// Which particles are held, by name, when there are few of them.
	if (fixed > 0 && fixed <= 8) {
		printf("  held      ");
		for (int32_t i = 0, shown = 0; i < n; i++) {
			sm_particle_def p;
			sm_model_get_particle(model, i, &p);
			if (p.motion == SM_PARTICLE_FREE)
				continue;
			printf("%s", shown++ > 0 ? ", " : " ");
			print_particle(doc, i);
		}
		printf("\n");
	}
	printf("springs      %d: %d rest-length, %d zero-length; %d with per-strain stiffness, ", (int)m,
	       (int)rest_length, (int)zero_length, (int)per_strain);
	if (per_section > 0)
		printf("%d per section, ", (int)per_section);
	printf("%d breakable\n", (int)breakable);
	const int32_t structures = sm_document_structure_count(doc);
	if (structures > 0) {
		printf("structures   %d\n", (int)structures);
		for (int32_t k = 0; k < structures; k++) {
			const sm_structure_info s = sm_document_structure(doc, k);
			print_structure(&s, sm_document_structure_file(doc, k));
		}
	}
	printf("total mass   %.6g kg\n", sm_model_total_mass(model));
	const sm_model_def def = sm_model_get_def(model);
	printf("gravity      (%g, %g, %g) m/s^2, mass damping %g 1/s\n", def.gravity[0], def.gravity[1],
	       def.gravity[2], def.mass_damping);
	// What the file's "loads" add to the weight.
	double total[3];
	const int32_t loaded = cli_total_load(model, total);
	if (loaded > 0)
		printf("loads        on %d particle%s, (%g, %g, %g) N in all\n", (int)loaded, loaded > 1 ? "s" : "",
		       total[0], total[1], total[2]);
	const int32_t ports = sm_document_port_count(doc);
	printf("ports        %d\n", (int)ports);
	for (int32_t k = 0; k < ports; k++) {
		const sm_port port = sm_document_port(doc, k);
		printf("  %-12s %-6s at ", port.name, port_kind(port.kind));
		print_particle(doc, port.particle);
		printf("\n");
	}
	const int32_t parameters = sm_document_parameter_count(doc);
	printf("parameters   %d\n", (int)parameters);
	for (int32_t k = 0; k < parameters; k++) {
		// What the parameter feeds, in the words of model_file.h's sm_parameter_use.
		static const char* const uses[] = {"constants", "initial state", "held particles",     "counts",
		                                   "settings",  "spring kinds",  "particle references"};
		const uint32_t used = sm_document_parameter_uses(doc, k);
		// The value as it reads back exactly: 4999.999 is not 5000.
		char value[SM_NUMBER_TEXT_CAPACITY], with_unit[SM_NUMBER_TEXT_CAPACITY + 16];
		sm_format_number(sm_document_parameter_value(doc, k), value);
		// With the unit of what it stands for, but for a ratio's "1".
		const char* unit = sm_document_parameter_unit(doc, k);
		const bool shown = unit[0] != '\0' && strcmp(unit, "1") != 0;
		snprintf(with_unit, sizeof with_unit, "%s%s%s", value, shown ? " " : "", shown ? unit : "");
		printf("  %-12s = %-12s feeds ", sm_document_parameter_name(doc, k), with_unit);
		if (used == 0)
			printf("nothing");
		for (int u = 0, shown = 0; u < (int)(sizeof uses / sizeof uses[0]); u++)
			if (used & (1u << u))
				printf("%s%s", shown++ ? ", " : "", uses[u]);
		printf("\n");
	}
	if (stiffest >= 0) {
		sm_spring_def s;
		sm_model_get_spring(model, stiffest, &s);
		printf("stiffest     spring %d, %.6g N/m, between ", (int)stiffest, max_stiffness);
		print_particle(doc, s.a);
		printf(" and ");
		print_particle(doc, s.b);
		printf("\n");
	}
	if (fastest >= 0) {
		sm_spring_def s;
		sm_model_get_spring(model, fastest, &s);
		if (isfinite(max_omega))
			printf("fastest      sqrt(k/m) = %.6g rad/s (%.6g Hz) at spring %d, between ", max_omega,
			       max_omega / (2.0 * 3.14159265358979323846), (int)fastest);
		else
			printf("fastest      sqrt(k/m) overflows at spring %d, between ", (int)fastest);
		print_particle(doc, s.a);
		printf(" and ");
		print_particle(doc, s.b);
		printf("\n");
	}
	sm_explicit_limit limit;
	if (sm_model_explicit_limit(model, &limit) != SM_OK) {
		fprintf(stderr, "springmass check: out of memory\n");
		sm_model_destroy(model);
		sm_document_destroy(doc);
		return 1;
	}
	if (limit.omega_max > 0.0 && isfinite(limit.omega_max))
		printf("omega_max    <= %.6g rad/s (%.6g Hz; Gershgorin bound, undamped)\n", limit.omega_max,
		       limit.omega_max / (2.0 * 3.14159265358979323846));
	if (isfinite(limit.step) && limit.step > 0.0)
		printf(
		    "explicit     stable with symplectic Euler at steps up to at least %.3g s (damping rate <= %.3g 1/s; "
		    "springmass modes MODEL -n 0: a closer value)\n",
		    limit.step, limit.damping_rate);
	// A valid file all the same, but one no integrator can follow: its time scale is below 1e-154 s.
	if (!isfinite(max_omega) || !isfinite(limit.omega_max))
		printf(
		    "warning      the highest frequency overflows a double (a stiffness / mass ratio above 1.8e308 "
		    "1/s^2): no integrator can simulate the model\n");
	// Adams' fixed-point iteration uses no linear solver, whatever the file names: the method then
	// takes the solver's place, as in the summary of springmass run.
	// CVODE's history kept where inputs jump is named; restarting there is the default. So is
	// BDF's stability limit detection switched off.
	printf("simulation   stop time %g s, output interval %g s, rtol %g, %s%s%s%s\n", settings.stop_time,
	       settings.output_interval, settings.solver.relative_tolerance,
	       settings.solver.method == SM_METHOD_ADAMS ? "method adams (fixed point, no linear solver)"
	                                                 : "solver ",
	       settings.solver.method == SM_METHOD_ADAMS ? "" : sm_linear_solver_name(settings.solver.solver),
	       settings.solver.restart_on_input_change ? "" : ", history kept where inputs jump",
	       settings.solver.method == SM_METHOD_BDF && !settings.solver.stability_limit_detection
	           ? ", stability limit detection off"
			   : "");
	cli_warn_coarse_tolerances(stdout, "warning      ", model, &settings.solver);
	bool overflows = false;
	bool memory = warn_coincident_mesh_vertices(doc, model) && warn_broken_at_start(doc, model) &&
	              warn_overflow_at_start(doc, model, &overflows);
	// A run that stops at t = 0 asks nothing of its tolerances (and a force over a tiny mass has
	// a round-off beyond any).
	if (memory && !overflows)
		cli_warn_tight_tolerances(stdout, "warning      ", doc, model, &settings.solver);
	// The notes after every warning.
	memory = memory && note_parallel_springs(doc, model);
	if (!memory) {
		fprintf(stderr, "springmass check: out of memory\n");
		sm_model_destroy(model);
		sm_document_destroy(doc);
		return 1;
	}
	printf("ok\n");
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return 0;
}

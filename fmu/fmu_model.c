// springmass FMU: variable table, GUID and modelDescription.xml (see fmu_model.h).
#define _POSIX_C_SOURCE 200809L

#include "fmu_model.h"
#include "fmu_text.h"

#include <ctype.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// GUID: FNV-1a with 128-bit state. The FNV-128 prime is 2^88 + 2^8 + 0x3b = 2^88 + 0x13b, so
// h * prime = h * 0x13b + (h << 88), done on two 64-bit halves (hi, lo) modulo 2^128.
// ---------------------------------------------------------------------------------------------

static void multiply_small(uint64_t hi, uint64_t lo, uint32_t factor, uint64_t* out_hi, uint64_t* out_lo)
{
	// lo * factor as a 96-bit number: split lo into 32-bit halves.
	uint64_t lo_lo = (lo & 0xffffffffu) * factor;
	uint64_t lo_hi = (lo >> 32) * factor;
	uint64_t low = lo_lo + (lo_hi << 32);
	uint64_t carry = (lo_hi >> 32) + (low < lo_lo ? 1u : 0u);
	*out_lo = low;
	*out_hi = hi * factor + carry;
}

typedef struct fnv128 {
	uint64_t hi, lo;
} fnv128;

static void fnv128_update(fnv128* h, const char* bytes, size_t length)
{
	for (size_t i = 0; i < length; ++i) {
		h->lo ^= (uint8_t)bytes[i];
		uint64_t p_hi, p_lo;
		multiply_small(h->hi, h->lo, 0x13bu, &p_hi, &p_lo);
		p_hi += h->lo << 24;  // (lo << 88) contributes lo << 24 to the high half
		h->hi = p_hi;
		h->lo = p_lo;
	}
}

void fmu_package_guid(const char* text, size_t length, const char* parameters, size_t parameters_length,
                      char guid[40])
{
	fnv128 h = {0x6c62272e07bb0142u, 0x62b821756295c58du};  // FNV-128 offset basis
	// The version first: another springmass may make another variable table of the same file, and
	// the GUID is what tells an importer that a modelDescription.xml and a binary belong together.
	char version[48];
	const int n = snprintf(version, sizeof version, "springmass %d.%d.%d", SM_VERSION_MAJOR, SM_VERSION_MINOR,
	                       SM_VERSION_PATCH);
	fnv128_update(&h, version, (size_t)n + 1);  // with its NUL
	fnv128_update(&h, text, length);
	if (parameters) {
		fnv128_update(&h, "", 1);
		fnv128_update(&h, parameters, parameters_length);
	}
	const uint64_t hi = h.hi, lo = h.lo;
	snprintf(guid, 40, "{%08x-%04x-%04x-%04x-%04x%08x}", (unsigned)(hi >> 32),
	         (unsigned)((hi >> 16) & 0xffffu), (unsigned)(hi & 0xffffu), (unsigned)(lo >> 48),
	         (unsigned)((lo >> 32) & 0xffffu), (unsigned)(lo & 0xffffffffu));
}

// ---------------------------------------------------------------------------------------------
// Names
// ---------------------------------------------------------------------------------------------

static char* duplicate(const char* s)
{
	size_t n = strlen(s) + 1;
	char* copy = malloc(n);
	if (copy)
		memcpy(copy, s, n);
	return copy;
}

static char* format(const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static char* format(const char* fmt, ...)
{
	va_list args;
	va_start(args, fmt);
	int n = vsnprintf(NULL, 0, fmt, args);
	va_end(args);
	if (n < 0)
		return NULL;
	char* s = malloc((size_t)n + 1);
	if (!s)
		return NULL;
	va_start(args, fmt);
	vsnprintf(s, (size_t)n + 1, fmt, args);
	va_end(args);
	return s;
}

// The keywords of C (C11 and C23), which no identifier may be.
static bool is_c_keyword(const char* s)
{
	static const char keywords[] =
	    " alignas alignof auto bool break case char const constexpr continue default do double else enum"
	    " extern false float for goto if inline int long nullptr register restrict return short signed"
	    " sizeof static static_assert struct switch thread_local true typedef typeof typeof_unqual union"
	    " unsigned void volatile while _Alignas _Alignof _Atomic _BitInt _Bool _Complex _Decimal128"
	    " _Decimal32 _Decimal64 _Generic _Imaginary _Noreturn _Static_assert _Thread_local ";
	const size_t n = strlen(s);
	// One word: a run of keywords ("long double") is none.
	for (const char* at = n > 0 && strchr(s, ' ') == NULL ? strstr(keywords + 1, s) : NULL; at != NULL;
	     at = strstr(at + 1, s))
		if (at[-1] == ' ' && at[n] == ' ')
			return true;
	return false;
}

char* fmu_identifier(const char* name)
{
	size_t n = name ? strlen(name) : 0;
	char* id = malloc(n + 7);
	if (!id)
		return NULL;
	// The name with every other character than a letter or a digit made '_', after the prefix's
	// room; then the prefix where the result is no identifier or a keyword ("thread local").
	for (size_t i = 0; i < n; ++i) {
		unsigned char c = (unsigned char)name[i];
		id[6 + i] = (char)(isalnum(c) ? c : '_');
	}
	id[6 + n] = '\0';
	const bool prefix = n == 0 || isdigit((unsigned char)id[6]) || is_c_keyword(id + 6);
	if (prefix)
		memcpy(id, "model_", 6);
	else
		memmove(id, id + 6, n + 1);
	return id;
}

// A name usable as one part of a structured name: an identifier as is, anything else quoted
// ('...' with ' and \ escaped), as the structured naming convention of FMI 2.0 allows.
static bool is_identifier(const char* s)
{
	if (!s || !*s || !(isalpha((unsigned char)s[0]) || s[0] == '_'))
		return false;
	for (const char* c = s; *c; ++c) {
		if (!(isalnum((unsigned char)*c) || *c == '_'))
			return false;
	}
	return true;
}

static char* name_part(const char* s)
{
	if (is_identifier(s))
		return duplicate(s);
	size_t n = strlen(s);
	char* q = malloc(2 * n + 3);
	if (!q)
		return NULL;
	size_t k = 0;
	q[k++] = '\'';
	for (size_t i = 0; i < n; ++i) {
		if (s[i] == '\'' || s[i] == '\\')
			q[k++] = '\\';
		q[k++] = s[i];
	}
	q[k++] = '\'';
	q[k] = '\0';
	return q;
}

// ---------------------------------------------------------------------------------------------
// Units
// ---------------------------------------------------------------------------------------------

// Units with their exponents of the SI base units kg, m, s.
typedef struct unit_definition {
	const char* name;
	int kg, m, s;
} unit_definition;

// Those of the outputs and settings, and those the model file's keys give parameters
// (sm_document_parameter_unit).
static const unit_definition units[] = {
    {"m", 0, 1, 0},      {"m/s", 0, 1, -1},  {"N", 1, 1, -2},     {"J", 1, 2, -2},
    {"s", 0, 0, 1},      {"1", 0, 0, 0},     {"kg", 1, 0, 0},     {"kg/m", 1, -1, 0},
    {"kg/m2", 1, -2, 0}, {"m/s2", 0, 1, -2}, {"1/s", 0, 0, -1},   {"N/m", 1, 0, -2},
    {"N/m2", 1, -1, -2}, {"N.s", 1, 1, -1},  {"N.s/m", 1, 0, -1}, {"N.s/m2", 1, -1, -1},
};

// The definition's own copy of a unit's name, NULL for "" or a unit it does not define.
static const char* defined_unit(const char* unit)
{
	for (size_t u = 0; unit != NULL && u < sizeof units / sizeof units[0]; ++u)
		if (strcmp(units[u].name, unit) == 0)
			return units[u].name;
	return NULL;
}

// ---------------------------------------------------------------------------------------------
// Tunability of parameters
// ---------------------------------------------------------------------------------------------

// What a model-file parameter feeds, as far as the FMU is concerned; the larger value wins.
typedef enum parameter_role {
	ROLE_CONSTANTS = 0,  // stiffness, damping, masses, rest lengths, gravity, loads: tunable
	ROLE_STATE,          // the initial state, which particles are held, settings, a spring's kind: fixed
	ROLE_STRUCTURE,      // counts of particles and springs, which particles springs join and ports
	                     // name: constant
} parameter_role;

// What a parameter is to the FMU, from the places the model file names it
// (sm_document_parameter_uses, which does not depend on the value): a count or an index in a
// particle reference makes it a constant, anything but constants makes it fixed. An unused
// parameter feeds nothing and stays tunable.
static parameter_role parameter_role_of(const sm_document* doc, int32_t parameter)
{
	const uint32_t uses = sm_document_parameter_uses(doc, parameter);
	if (uses & (SM_PARAMETER_COUNTS | SM_PARAMETER_PARTICLE_REFERENCES))
		return ROLE_STRUCTURE;
	if (uses & ~(uint32_t)SM_PARAMETER_CONSTANTS)
		return ROLE_STATE;
	return ROLE_CONSTANTS;
}

// The role of a model-file parameter and what makes it so, for its variable's description: a
// fixed parameter names each of its uses beyond constants, a constant each of its uses that set
// the structure (a rest length that chooses a spring's law is fixed for that alone, an index
// that names a spring's end a constant for that alone).
#define PARAMETER_ROLE_TEXT_CAPACITY 192
static void describe_parameter_role(uint32_t uses, parameter_role role,
                                    char text[PARAMETER_ROLE_TEXT_CAPACITY])
{
	static const struct {
		uint32_t use;
		const char* words;
	} fixed_uses[] = {{SM_PARAMETER_INITIAL_STATE, "the initial state"},
	                  {SM_PARAMETER_MOTION, "which particles are held"},
	                  {SM_PARAMETER_SPRING_KINDS, "a spring's kind (rest length 0 or not)"},
	                  {SM_PARAMETER_SETTINGS, "the simulation settings"}},
	  structure_uses[] = {{SM_PARAMETER_COUNTS, "a count"},
	                      {SM_PARAMETER_PARTICLE_REFERENCES, "which particle a reference names"}};
	if (role == ROLE_CONSTANTS) {
		snprintf(text, PARAMETER_ROLE_TEXT_CAPACITY, "tunable: feeds constants only");
		return;
	}
	const bool fixed = role == ROLE_STATE;
	const size_t count =
	    fixed ? sizeof fixed_uses / sizeof fixed_uses[0] : sizeof structure_uses / sizeof structure_uses[0];
	const char* words[4];
	size_t n = 0;
	for (size_t k = 0; k < count; k++)
		if (uses & (fixed ? fixed_uses[k].use : structure_uses[k].use))
			words[n++] = fixed ? fixed_uses[k].words : structure_uses[k].words;
	int used = snprintf(text, PARAMETER_ROLE_TEXT_CAPACITY, "%s",
	                    fixed ? "fixed: feeds " : "constant: sets the model's structure (");
	for (size_t k = 0; k < n; k++)
		used += snprintf(text + used, PARAMETER_ROLE_TEXT_CAPACITY - (size_t)used, "%s%s",
		                 k == 0       ? ""
		                 : k + 1 == n ? " and "
		                              : ", ",
		                 words[k]);
	if (!fixed)
		snprintf(text + used, PARAMETER_ROLE_TEXT_CAPACITY - (size_t)used, "), fixed at packaging");
}

// ---------------------------------------------------------------------------------------------
// The table
// ---------------------------------------------------------------------------------------------

typedef struct builder {
	fmu_table* table;
	int32_t capacity;
	bool failed;
} builder;

static fmu_variable* add(builder* b, char* name, char* description, fmu_type type, fmu_causality causality,
                         fmu_variability variability, const char* unit, fmu_source source, int32_t index,
                         int32_t component)
{
	if (b->failed || !name || !description) {
		free(name);
		free(description);
		b->failed = true;
		return NULL;
	}
	fmu_table* t = b->table;
	if (t->count == b->capacity) {
		int32_t capacity = b->capacity ? 2 * b->capacity : 64;
		fmu_variable* grown = realloc(t->variables, (size_t)capacity * sizeof *grown);
		if (!grown) {
			free(name);
			free(description);
			b->failed = true;
			return NULL;
		}
		t->variables = grown;
		b->capacity = capacity;
	}
	fmu_variable* v = &t->variables[t->count++];
	memset(v, 0, sizeof *v);
	v->name = name;
	v->description = description;
	v->type = type;
	v->causality = causality;
	v->variability = variability;
	v->unit = unit;
	v->source = source;
	v->index = index;
	v->component = component;
	return v;
}

static void add_real_parameter(builder* b, const char* name, const char* description, const char* unit,
                               fmu_source source, double start)
{
	fmu_variable* v = add(b, duplicate(name), duplicate(description), FMU_REAL, FMU_PARAMETER, FMU_FIXED,
	                      unit, source, 0, 0);
	if (v) {
		v->has_start = true;
		v->start_real = start;
	}
}

// The range fmi2SetReal and fmi2SetInteger accept for a solver setting (fmu_values.c), declared as
// its min and max (FMI 2.0, 2.2.7; both bounds are inclusive, so a relative tolerance below 1 has
// the double just below 1 as its max); NAN where no bound is declared.
static void solver_range(fmu_source source, double* min, double* max)
{
	*min = *max = NAN;
	switch (source) {
	case FMU_SRC_SOLVER_RTOL:
		*min = SM_MIN_RELATIVE_TOLERANCE;
		*max = nextafter(1.0, 0.0);
		break;
	case FMU_SRC_SOLVER_ATOL_POSITION:
	case FMU_SRC_SOLVER_ATOL_VELOCITY: *min = SM_MIN_ABSOLUTE_TOLERANCE; break;
	case FMU_SRC_SOLVER_MAX_STEP: *min = 0.0; break;
	case FMU_SRC_SOLVER_MAX_STEPS:
	case FMU_SRC_SOLVER_THREADS: *min = 1.0; break;
	default: break;
	}
}

// Appends ` min="..." max="..."` for the bounds of solver_range that are declared.
static void append_range(fmu_text* out, const fmu_variable* v)
{
	double bound[2];
	solver_range(v->source, &bound[0], &bound[1]);
	for (int k = 0; k < 2; k++)
		if (!isnan(bound[k])) {
			char text[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(bound[k], text);
			fmu_text_appendf(out, " %s=\"%s\"", k == 0 ? "min" : "max", text);
		}
}

static void add_string_parameter(builder* b, const char* name, const char* description, fmu_source source,
                                 const char* start)
{
	fmu_variable* v = add(b, duplicate(name), duplicate(description), FMU_STRING, FMU_PARAMETER, FMU_FIXED,
	                      NULL, source, 0, 0);
	if (v) {
		v->has_start = true;
		v->start_string = start;
	}
}

static const char* const axis[3] = {"x", "y", "z"};
static const char* const velocity_axis[3] = {"vx", "vy", "vz"};
static const char* const force_axis[3] = {"fx", "fy", "fz"};

static void add_port(builder* b, const sm_document* doc, const sm_model* model, int32_t port_index)
{
	sm_port port = sm_document_port(doc, port_index);
	char* part = name_part(port.name);
	if (!part) {
		b->failed = true;
		return;
	}
	sm_particle_def particle = sm_default_particle_def();
	sm_model_get_particle(model, port.particle, &particle);
	const char* particle_name = sm_document_particle_name(doc, port.particle);
	char particle_label[64];
	if (!particle_name) {
		snprintf(particle_label, sizeof particle_label, "particle %d", (int)port.particle);
		particle_name = particle_label;
	}
	bool motion = port.kind == SM_PORT_MOTION;
	fmu_causality kinematic = motion ? FMU_INPUT : FMU_OUTPUT;
	for (int c = 0; c < 3; ++c) {
		fmu_variable* v =
		    add(b, format("%s.%s", part, axis[c]),
			    format("%s of %s, %s port at particle %s", axis[c], port.name,
			           motion ? "position prescribed at the motion" : "position at the", particle_name),
			    FMU_REAL, kinematic, FMU_CONTINUOUS, "m", FMU_SRC_PORT_POSITION, port_index, c);
		if (v && motion) {
			v->has_start = true;
			v->start_real = particle.position[c];
		}
	}
	for (int c = 0; c < 3; ++c) {
		fmu_variable* v =
		    add(b, format("%s.%s", part, velocity_axis[c]),
			    format("%s-velocity of %s, %s port at particle %s", axis[c], port.name,
			           motion ? "prescribed at the motion" : "at the", particle_name),
			    FMU_REAL, kinematic, FMU_CONTINUOUS, "m/s", FMU_SRC_PORT_VELOCITY, port_index, c);
		if (v && motion) {
			v->has_start = true;
			v->start_real = particle.velocity[c];
		}
	}
	if (port.kind != SM_PORT_PROBE) {
		for (int c = 0; c < 3; ++c) {
			fmu_variable* v =
			    add(b, format("%s.%s", part, force_axis[c]),
				    motion ? format("%s-force the model exerts on whatever drives %s (particle %s)", axis[c],
				                    port.name, particle_name)
				           : format("%s-force applied from outside at %s (particle %s)", axis[c], port.name,
				                    particle_name),
				    FMU_REAL, motion ? FMU_OUTPUT : FMU_INPUT, FMU_CONTINUOUS, "N", FMU_SRC_PORT_FORCE,
				    port_index, c);
			if (v && !motion) {
				v->has_start = true;
				v->start_real = 0.0;
			}
		}
	}
	free(part);
}

static int compare_neighbours(const void* left, const void* right)
{
	const int32_t a = ((const fmu_neighbour*)left)->port, b = ((const fmu_neighbour*)right)->port;
	return (a > b) - (a < b);
}

// The table's port_neighbours, port_force_terms and mass_damping. A motion port's force is that
// of the springs at its particle, of gravity, the loads and mass damping on it: each spring's
// elastic force ks (L - l0) u depends on the positions of both its ends, its damping force
// kd (u . dv) u on their positions (through u) and velocities; mass damping -alpha m v along x on
// the particle's own velocity along x (and so on); gravity and the loads on nothing. A spring
// whose stiffness and damping are both the number 0 (sm_document_force_terms) adds no
// dependency, and a zero-length spring's force, evaluated as ks L u, changes in its last bits with
// every component of the positions: a position is listed whole. Which springs exist and which
// particle each port is at do not change in the FMU (springs that break only remove
// dependencies). False when out of memory.
static bool find_port_neighbours(const sm_document* doc, const sm_model* model, fmu_table* t)
{
	const int32_t ports = sm_document_port_count(doc);
	const int32_t particles = sm_model_particle_count(model);
	const int32_t springs = sm_model_spring_count(model);
	t->port_count = ports;
	t->port_neighbour_start = calloc((size_t)ports + 1, sizeof *t->port_neighbour_start);
	t->port_force_terms = calloc((size_t)ports + 1, sizeof *t->port_force_terms);
	int32_t* motion_port = malloc(((size_t)particles + 1) * sizeof *motion_port);
	int32_t* next = malloc(((size_t)ports + 1) * sizeof *next);
	uint8_t* terms = malloc((size_t)springs + 1);
	bool ok = t->port_neighbour_start && t->port_force_terms && motion_port && next && terms;
	int32_t* start = t->port_neighbour_start;
	if (ok)
		t->mass_damping = sm_document_force_terms(doc, terms);
	for (int32_t i = 0; ok && i < particles; ++i)
		motion_port[i] = -1;
	for (int32_t p = 0; ok && p < ports; ++p) {
		const sm_port port = sm_document_port(doc, p);
		if (port.kind == SM_PORT_MOTION)
			motion_port[port.particle] = p;
	}
	// Counted, then filled, each spring of some force at a motion port's particle adding its terms
	// to the port's own, and each such spring between two motion ports' particles adding each port
	// to the other's list.
	for (int pass = 0; ok && pass < 2; ++pass) {
		for (int32_t k = 0; k < springs; ++k) {
			sm_spring_def spring = sm_default_spring_def();
			sm_model_get_spring(model, k, &spring);
			const int32_t a = motion_port[spring.a], b = motion_port[spring.b];
			if (terms[k] == 0)
				continue;
			if (pass == 0) {
				if (a >= 0)
					t->port_force_terms[a] |= terms[k];
				if (b >= 0)
					t->port_force_terms[b] |= terms[k];
			}
			if (a < 0 || b < 0)
				continue;
			if (pass == 0) {
				++start[a + 1];
				++start[b + 1];
			} else {
				t->port_neighbours[next[a]++] = (fmu_neighbour){b, terms[k]};
				t->port_neighbours[next[b]++] = (fmu_neighbour){a, terms[k]};
			}
		}
		if (pass == 0) {
			for (int32_t p = 0; p < ports; ++p)
				start[p + 1] += start[p];
			memcpy(next, start, ((size_t)ports + 1) * sizeof *next);
			t->port_neighbours = malloc(((size_t)start[ports] + 1) * sizeof *t->port_neighbours);
			ok = t->port_neighbours != NULL;
		}
	}
	// Each list in order, a port joined by several springs once, with all their terms.
	for (int32_t p = 0, kept = 0; ok && p < ports; ++p) {
		const int32_t first = start[p], end = start[p + 1];
		fmu_neighbour* list = t->port_neighbours;
		qsort(list + first, (size_t)(end - first), sizeof *list, compare_neighbours);
		start[p] = kept;
		for (int32_t k = first; k < end; ++k) {
			if (k == first || list[k].port != list[kept - 1].port)
				list[kept++] = list[k];
			else
				list[kept - 1].terms |= list[k].terms;
		}
		if (p + 1 == ports)
			start[ports] = kept;
	}
	free(motion_port);
	free(next);
	free(terms);
	return ok;
}

// The table's port_potential_terms: the terms of the potential energy each port's particle
// enters (sm_document_potential_terms). False when out of memory.
static bool find_port_potential_terms(const sm_document* doc, fmu_table* t)
{
	const int32_t ports = sm_document_port_count(doc);
	uint8_t* terms = malloc((size_t)sm_document_particle_count(doc) + 1);
	t->port_potential_terms = malloc((size_t)ports + 1);
	const bool ok = terms && t->port_potential_terms;
	if (ok) {
		sm_document_potential_terms(doc, terms);
		for (int32_t p = 0; p < ports; ++p)
			t->port_potential_terms[p] = terms[sm_document_port(doc, p).particle];
	}
	free(terms);
	return ok;
}

static sm_status fail(sm_error* err, sm_status status, const char* message)
{
	if (err) {
		err->status = status;
		snprintf(err->message, sizeof err->message, "%s", message);
	}
	return status;
}

// A node of the structured names' tree (FMI 2.0, 2.2.9): a.b is field b of the record a, a[i]
// element i of the array a. Every name is a leaf (kind 0), and each of its prefixes that ends
// before an unquoted '.' or '[' is a record ('.') or an array ('[').
typedef struct name_node {
	const char* name;
	size_t length;
	char kind;
} name_node;

// Appends the nodes of one name; quoted parts ('...' with \ escapes) are skipped whole.
static size_t name_nodes(const char* name, name_node* out)
{
	size_t n = 0;
	bool quoted = false;
	for (size_t k = 0; name[k] != '\0'; ++k) {
		if (quoted && name[k] == '\\' && name[k + 1] != '\0')
			++k;
		else if (name[k] == '\'')
			quoted = !quoted;
		else if (!quoted && (name[k] == '.' || name[k] == '[') && k > 0)
			out[n++] = (name_node){name, k, name[k]};
	}
	out[n++] = (name_node){name, strlen(name), 0};
	return n;
}

// Orders nodes by their name (the first length bytes), then their kind.
static int compare_nodes(const void* left, const void* right)
{
	const name_node* a = left;
	const name_node* b = right;
	const int order = memcmp(a->name, b->name, a->length < b->length ? a->length : b->length);
	if (order != 0)
		return order;
	if (a->length != b->length)
		return a->length < b->length ? -1 : 1;
	return (a->kind > b->kind) - (a->kind < b->kind);
}

static const char* node_kind(char kind)
{
	return kind == '.' ? "a record" : kind == '[' ? "an array" : "a variable";
}

// The first `length` bytes of a name, quoted for a message as the model file's messages quote
// names: one longer than QUOTED_NAME_BYTES is cut with "..." after the quote, so that a message
// naming three long names keeps its end. The names are made of C identifiers (parameters, ports,
// structures; docs/model-format.md) and ASCII suffixes: every byte is a character. Returns out.
#define QUOTED_NAME_BYTES 80
static const char* quoted_name(char out[QUOTED_NAME_BYTES + 6], const char* name, size_t length)
{
	const size_t shown = length > QUOTED_NAME_BYTES ? QUOTED_NAME_BYTES : length;
	snprintf(out, QUOTED_NAME_BYTES + 6, "\"%.*s\"%s", (int)shown, name, shown < length ? "..." : "");
	return out;
}

// The names must form a tree, as modelDescription.xml declares (variableNamingConvention
// "structured"): no name twice, and no name that is also a record or an array, or a record and an
// array at once. A parameter "energy" beside "energy.kinetic", or a port "p" ("p.x") beside the
// particles' "p[0].x", is refused. The nodes of the non-particle variables are sorted (particle
// variables "p[i].x" add the array p and cannot collide with each other).
static sm_status check_unique_names(const fmu_table* t, sm_error* err)
{
	size_t capacity = 1, count = 0;
	bool particles = false;
	for (int32_t i = 0; i < t->count; ++i) {
		if (t->variables[i].source == FMU_SRC_PARTICLE_POSITION ||
		    t->variables[i].source == FMU_SRC_PARTICLE_VELOCITY)
			particles = true;
		else
			capacity += strlen(t->variables[i].name) + 1;
	}
	name_node* nodes = malloc(capacity * sizeof *nodes);
	if (!nodes)
		return fail(err, SM_ERROR_OUT_OF_MEMORY, "out of memory while checking the FMU's variable names");
	if (particles)
		nodes[count++] = (name_node){"p[0].x", 1, '['};
	for (int32_t i = 0; i < t->count; ++i)
		if (t->variables[i].source != FMU_SRC_PARTICLE_POSITION &&
		    t->variables[i].source != FMU_SRC_PARTICLE_VELOCITY)
			count += name_nodes(t->variables[i].name, nodes + count);
	// Sorted, equal names lie side by side, a leaf first, then a record, then an array.
	qsort(nodes, count, sizeof *nodes, compare_nodes);
	for (size_t i = 1; i < count; ++i) {
		const name_node* a = &nodes[i - 1];
		const name_node* b = &nodes[i];
		if (a->length != b->length || memcmp(a->name, b->name, a->length) != 0 ||
		    (a->kind == b->kind && a->kind))
			continue;
		if (err) {
			char first[QUOTED_NAME_BYTES + 6], second[QUOTED_NAME_BYTES + 6], node[QUOTED_NAME_BYTES + 6];
			quoted_name(first, a->name, strlen(a->name));
			quoted_name(second, b->name, strlen(b->name));
			quoted_name(node, a->name, a->length);
			err->status = SM_ERROR_SCHEMA;
			if (!a->kind && !b->kind)
				snprintf(
				    err->message, sizeof err->message,
				    "FMU variable name %s is used twice (rename the parameter or port; names must be unique)",
				    first);
			else
				snprintf(
				    err->message, sizeof err->message,
				    "FMU variable names %s and %s clash: %s would be both %s and %s of the structured names "
				    "(rename the parameter or port)",
				    first, second, node, node_kind(a->kind), node_kind(b->kind));
		}
		free(nodes);
		return SM_ERROR_SCHEMA;
	}
	free(nodes);
	return SM_OK;
}

// Sets err to prefix and the formatted message (cut to the message's capacity); returns status.
static sm_status fail_with(sm_error* err, sm_status status, const char* prefix, const char* fmt, va_list args)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 0)))
#endif
    ;

static sm_status fail_with(sm_error* err, sm_status status, const char* prefix, const char* fmt, va_list args)
{
	if (err) {
		err->status = status;
		int n = snprintf(err->message, sizeof err->message, "%s", prefix);
		if (n >= 0 && (size_t)n < sizeof err->message)
			vsnprintf(err->message + n, sizeof err->message - (size_t)n, fmt, args);
	}
	return status;
}

static sm_status failf(sm_error* err, sm_status status, const char* fmt, ...)
{
	va_list args;
	va_start(args, fmt);
	fail_with(err, status, "", fmt, args);
	va_end(args);
	return status;
}

sm_status fmu_table_create(const sm_document* doc, const char* text, size_t length, const char* parameters,
                           size_t parameters_length, fmu_table* table, sm_error* err)
{
	memset(table, 0, sizeof *table);
	if (!doc || !text)
		return fail(err, SM_ERROR_INVALID_ARGUMENT, "no model file");
	sm_error build_err = {SM_OK, ""};
	sm_model* model = NULL;
	sm_status st = sm_document_build(doc, &model, &build_err);
	if (st != SM_OK) {
		if (err)
			*err = build_err;
		return st;
	}
	fmu_package_guid(text, length, parameters, parameters_length, table->guid);
	sm_document_settings settings = sm_document_get_settings(doc);
	table->model_identifier = fmu_identifier(sm_document_name(doc));
	table->model_name = duplicate(sm_document_name(doc) ? sm_document_name(doc) : "");
	table->description = duplicate(sm_document_description(doc) ? sm_document_description(doc) : "");
	table->stop_time = settings.stop_time;
	table->step_size = settings.output_interval;
	table->tolerance = settings.solver.relative_tolerance;

	builder b = {table, 0, !table->model_identifier || !table->model_name || !table->description};

	// Model-file parameters.
	int32_t np = sm_document_parameter_count(doc);
	for (int32_t i = 0; i < np && !b.failed; ++i) {
		const char* pname = sm_document_parameter_name(doc, i);
		const parameter_role role = parameter_role_of(doc, i);
		char role_text[PARAMETER_ROLE_TEXT_CAPACITY];
		describe_parameter_role(sm_document_parameter_uses(doc, i), role, role_text);
		fmu_variable* v =
		    add(&b, name_part(pname), format("model-file parameter %s (%s)", pname, role_text), FMU_REAL,
			    role == ROLE_STRUCTURE ? FMU_LOCAL : FMU_PARAMETER,
			    role == ROLE_CONSTANTS ? FMU_TUNABLE
			    : role == ROLE_STATE   ? FMU_FIXED
			                           : FMU_CONSTANT,
			    defined_unit(sm_document_parameter_unit(doc, i)), FMU_SRC_MODEL_PARAMETER, i, 0);
		if (v) {
			v->has_start = true;
			v->start_real = sm_document_parameter_value(doc, i);
		}
	}

	// Integrator settings.
	const sm_simulation_def* s = &settings.solver;
	add_real_parameter(&b, "solver.rtol", "relative tolerance of CVODE", "1", FMU_SRC_SOLVER_RTOL,
	                   s->relative_tolerance);
	add_real_parameter(&b, "solver.atol_position", "absolute tolerance of positions", "m",
	                   FMU_SRC_SOLVER_ATOL_POSITION, s->absolute_tolerance_position);
	add_real_parameter(&b, "solver.atol_velocity", "absolute tolerance of velocities", "m/s",
	                   FMU_SRC_SOLVER_ATOL_VELOCITY, s->absolute_tolerance_velocity);
	add_real_parameter(&b, "solver.max_step", "largest internal step (0: unlimited)", "s",
	                   FMU_SRC_SOLVER_MAX_STEP, s->max_step);
	fmu_variable* max_steps =
	    add(&b, duplicate("solver.max_steps"), duplicate("internal steps allowed per communication step"),
		    FMU_INTEGER, FMU_PARAMETER, FMU_FIXED, NULL, FMU_SRC_SOLVER_MAX_STEPS, 0, 0);
	if (max_steps) {
		max_steps->has_start = true;
		max_steps->start_integer = s->max_steps;
	}
	fmu_variable* threads =
	    add(&b, duplicate("solver.threads"),
		    duplicate("threads for the pcg solver on models of 4000 free particles or more "
		              "(at most 4, no more than the processors; the results do not depend on it)"),
		    FMU_INTEGER, FMU_PARAMETER, FMU_FIXED, NULL, FMU_SRC_SOLVER_THREADS, 0, 0);
	if (threads) {
		threads->has_start = true;
		threads->start_integer = s->threads;
	}
	add_string_parameter(&b, "solver.method", "multistep method: bdf or adams", FMU_SRC_SOLVER_METHOD,
	                     sm_method_name(s->method));
	add_string_parameter(&b, "solver.linear_solver",
	                     "linear solver of BDF: auto, dense, klu, pcg or cholmod (Adams uses none)",
	                     FMU_SRC_SOLVER_LINEAR_SOLVER, sm_linear_solver_name(s->solver));
	add_string_parameter(&b, "solver.jacobian", "Jacobian: exact or definite (definiteness-preserving)",
	                     FMU_SRC_SOLVER_JACOBIAN, sm_jacobian_variant_name(s->jacobian));
	add_string_parameter(
	    &b, "solver.input_changes",
	    "an input that jumps: restart (re-initialise CVODE where its history cannot carry the "
	    "jump within the tolerances) or keep (its history)",
	    FMU_SRC_SOLVER_INPUT_CHANGES, sm_input_changes_name(s->restart_on_input_change));
	fmu_variable* detection =
	    add(&b, duplicate("solver.stability_limit_detection"),
		    duplicate("BDF lowers its order where its steps would go unstable on lightly damped vibrations "
		              "(CVODE's stability limit detection; Adams ignores it)"),
		    FMU_BOOLEAN, FMU_PARAMETER, FMU_FIXED, NULL, FMU_SRC_SOLVER_STABILITY, 0, 0);
	if (detection) {
		detection->has_start = true;
		detection->start_boolean = s->stability_limit_detection;
	}

	// Ports.
	int32_t nports = sm_document_port_count(doc);
	for (int32_t i = 0; i < nports && !b.failed; ++i)
		add_port(&b, doc, model, i);

	if (!b.failed && (!find_port_neighbours(doc, model, table) || !find_port_potential_terms(doc, table)))
		b.failed = true;

	// Energies.
	add(&b, duplicate("energy.kinetic"), duplicate("kinetic energy of all particles"), FMU_REAL, FMU_OUTPUT,
	    FMU_CONTINUOUS, "J", FMU_SRC_ENERGY_KINETIC, 0, 0);
	add(&b, duplicate("energy.elastic"), duplicate("elastic energy stored in the springs"), FMU_REAL,
	    FMU_OUTPUT, FMU_CONTINUOUS, "J", FMU_SRC_ENERGY_ELASTIC, 0, 0);
	add(&b, duplicate("energy.gravity"),
	    duplicate("potential energy of gravity and the loads (zero at the origin)"), FMU_REAL, FMU_OUTPUT,
	    FMU_CONTINUOUS, "J", FMU_SRC_ENERGY_GRAVITY, 0, 0);
	add(&b, duplicate("energy.dissipated"),
	    duplicate("energy dissipated since the start (damping, broken springs)"), FMU_REAL, FMU_OUTPUT,
	    FMU_CONTINUOUS, "J", FMU_SRC_ENERGY_DISSIPATED, 0, 0);
	add(&b, duplicate("energy.input"),
	    duplicate("work done by the inputs since the start (force ports on free particles, motion ports, "
	              "tunable parameters set between steps)"),
	    FMU_REAL, FMU_OUTPUT, FMU_CONTINUOUS, "J", FMU_SRC_ENERGY_INPUT, 0, 0);

	// Every particle's position and velocity, unless the model file switches them off.
	if (settings.particle_variables) {
		int32_t n = sm_model_particle_count(model);
		for (int32_t i = 0; i < n && !b.failed; ++i) {
			const char* pname = sm_document_particle_name(doc, i);
			for (int c = 0; c < 3; ++c) {
				add(&b, format("p[%d].%s", (int)i, axis[c]),
				    pname ? format("%s-position of particle %s", axis[c], pname)
				          : format("%s-position of particle %d", axis[c], (int)i),
				    FMU_REAL, FMU_LOCAL, FMU_CONTINUOUS, "m", FMU_SRC_PARTICLE_POSITION, i, c);
			}
			for (int c = 0; c < 3; ++c) {
				add(&b, format("p[%d].%s", (int)i, velocity_axis[c]),
				    pname ? format("%s-velocity of particle %s", axis[c], pname)
				          : format("%s-velocity of particle %d", axis[c], (int)i),
				    FMU_REAL, FMU_LOCAL, FMU_CONTINUOUS, "m/s", FMU_SRC_PARTICLE_VELOCITY, i, c);
			}
		}
	}
	sm_model_destroy(model);

	if (b.failed) {
		fmu_table_destroy(table);
		return fail(err, SM_ERROR_OUT_OF_MEMORY, "out of memory while building the FMU's variable table");
	}
	st = check_unique_names(table, err);
	if (st != SM_OK) {
		fmu_table_destroy(table);
		return st;
	}
	return SM_OK;
}

void fmu_table_destroy(fmu_table* table)
{
	if (!table)
		return;
	for (int32_t i = 0; i < table->count; ++i) {
		free(table->variables[i].name);
		free(table->variables[i].description);
	}
	free(table->variables);
	free(table->port_neighbour_start);
	free(table->port_neighbours);
	free(table->port_force_terms);
	free(table->port_potential_terms);
	free(table->model_identifier);
	free(table->model_name);
	free(table->description);
	memset(table, 0, sizeof *table);
}

// ---------------------------------------------------------------------------------------------
// modelDescription.xml
// ---------------------------------------------------------------------------------------------

const char* fmu_causality_name(fmu_causality c)
{
	switch (c) {
	case FMU_PARAMETER: return "parameter";
	case FMU_INPUT: return "input";
	case FMU_OUTPUT: return "output";
	case FMU_LOCAL: return "local";
	}
	return "local";
}

const char* fmu_variability_name(fmu_variability v)
{
	switch (v) {
	case FMU_CONSTANT: return "constant";
	case FMU_FIXED: return "fixed";
	case FMU_TUNABLE: return "tunable";
	case FMU_CONTINUOUS: return "continuous";
	}
	return "continuous";
}

static bool unit_used(const fmu_table* t, const char* unit)
{
	for (int32_t i = 0; i < t->count; ++i) {
		if (t->variables[i].unit && strcmp(t->variables[i].unit, unit) == 0)
			return true;
	}
	return false;
}

// Indices (1-based, as in ModelVariables) of the inputs an output depends on directly at a
// communication point. Positions and velocities of force and probe ports and the dissipated
// energy are states: no direct dependence. A motion port's force depends on the prescribed
// positions of its own port and of the motion ports a spring joins it to, if the springs have some
// stiffness or damping, on their velocities if the springs have some damping, and on its own
// velocity along the force's axis if mass damping can act (port_neighbours, port_force_terms,
// find_port_neighbours); kinetic energy on the motion ports' velocities (every mass is > 0); the
// elastic energy on the position of a motion port a spring of some stiffness ends at; the
// gravitational energy on a motion port's position along each axis the weight or a load on its
// particle can have a component (port_potential_terms); the inputs' work on all these (a motion
// set elsewhere does the work of the energy it adds at once). `first` holds each port's first
// variable, its x (a motion port's six inputs x, y, z, vx, vy, vz follow each other, and ports'
// variables follow the ports' order).
static void append_dependencies(fmu_text* out, const fmu_table* t, const fmu_variable* v,
                                const int32_t* first)
{
	// Which terms of the energy of a motion port's particle a position enters for the output.
	unsigned position = 0;
	bool velocity = false;
	const unsigned constant = SM_POTENTIAL_CONSTANT_X | SM_POTENTIAL_CONSTANT_Y | SM_POTENTIAL_CONSTANT_Z;
	switch (v->source) {
	case FMU_SRC_ENERGY_INPUT:
		position = constant | SM_POTENTIAL_ELASTIC;
		velocity = true;
		break;
	case FMU_SRC_ENERGY_KINETIC: velocity = true; break;
	case FMU_SRC_ENERGY_ELASTIC: position = SM_POTENTIAL_ELASTIC; break;
	case FMU_SRC_ENERGY_GRAVITY: position = constant; break;
	default: break;
	}
	fmu_text_append_string(out, " dependencies=\"");
	bool separator = false;
	if (v->source == FMU_SRC_PORT_FORCE) {
		// Its own port among its neighbours, in ascending order.
		const int32_t own = v->index;
		const fmu_neighbour* neighbour = t->port_neighbours + t->port_neighbour_start[own];
		const fmu_neighbour* end = t->port_neighbours + t->port_neighbour_start[own + 1];
		bool own_done = false;
		while (neighbour < end || !own_done) {
			fmu_neighbour port;
			if (!own_done && (neighbour == end || own < neighbour->port)) {
				port = (fmu_neighbour){own, t->port_force_terms[own]};
				own_done = true;
			} else {
				port = *neighbour++;
			}
			// Inputs x, y, z, then vx, vy, vz.
			for (int32_t k = 0; k < 6; ++k) {
				const bool listed = k < 3
				                        ? port.terms != 0
				                        : (port.terms & SM_FORCE_DAMPING) ||
				                              (port.port == own && t->mass_damping && k - 3 == v->component);
				if (listed) {
					fmu_text_appendf(out, separator ? " %d" : "%d", (int)(first[port.port] + k) + 1);
					separator = true;
				}
			}
		}
	}
	// States alone (a port's position and velocity, the dissipated energy): no input to look for.
	for (int32_t i = 0; (position || velocity) && i < t->count; ++i) {
		const fmu_variable* w = &t->variables[i];
		if (w->causality != FMU_INPUT)
			continue;
		// A position enters the elastic energy through all its components, the constant forces'
		// potential through those the force has.
		const unsigned terms = w->source == FMU_SRC_PORT_POSITION
		                           ? t->port_potential_terms[w->index] &
		                                 (SM_POTENTIAL_ELASTIC | (SM_POTENTIAL_CONSTANT_X << w->component))
		                           : 0;
		if ((position & terms) || (velocity && w->source == FMU_SRC_PORT_VELOCITY)) {
			fmu_text_appendf(out, separator ? " %d" : "%d", (int)i + 1);
			separator = true;
		}
	}
	fmu_text_append_string(out, "\"");
}

char* fmu_model_description(const fmu_table* t, const char* generation_date)
{
	fmu_text out = {NULL, 0, 0, false};
	fmu_text_append_string(&out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
	fmu_text_append_string(&out, "<fmiModelDescription\n  fmiVersion=\"2.0\"\n  modelName=\"");
	fmu_text_append_escaped(&out, t->model_name);
	fmu_text_appendf(&out, "\"\n  guid=\"%s\"\n  description=\"", t->guid);
	fmu_text_append_escaped(&out, t->description);
	fmu_text_appendf(&out, "\"\n  generationTool=\"springmass %s\"\n", SPRINGMASS_VERSION_STRING);
	if (generation_date)
		fmu_text_appendf(&out, "  generationDateAndTime=\"%s\"\n", generation_date);
	fmu_text_append_string(&out,
	                       "  variableNamingConvention=\"structured\"\n  numberOfEventIndicators=\"0\">\n");

	fmu_text_appendf(
	    &out,
	    "  <CoSimulation\n    modelIdentifier=\"%s\"\n    needsExecutionTool=\"false\"\n"
	    "    canHandleVariableCommunicationStepSize=\"true\"\n    canInterpolateInputs=\"true\"\n"
	    "    maxOutputDerivativeOrder=\"1\"\n    canRunAsynchronuously=\"false\"\n"
	    "    canBeInstantiatedOnlyOncePerProcess=\"false\"\n    canNotUseMemoryManagementFunctions=\"true\"\n"
	    "    canGetAndSetFMUstate=\"true\"\n    canSerializeFMUstate=\"true\"\n"
	    "    providesDirectionalDerivative=\"true\"/>\n",
	    t->model_identifier);

	fmu_text_append_string(&out, "  <UnitDefinitions>\n");
	for (size_t u = 0; u < sizeof units / sizeof units[0]; ++u) {
		if (!unit_used(t, units[u].name))
			continue;
		fmu_text_appendf(&out, "    <Unit name=\"%s\"><BaseUnit", units[u].name);
		if (units[u].kg)
			fmu_text_appendf(&out, " kg=\"%d\"", units[u].kg);
		if (units[u].m)
			fmu_text_appendf(&out, " m=\"%d\"", units[u].m);
		if (units[u].s)
			fmu_text_appendf(&out, " s=\"%d\"", units[u].s);
		fmu_text_append_string(&out, "/></Unit>\n");
	}
	fmu_text_append_string(&out, "  </UnitDefinitions>\n");

	fmu_text_append_string(
	    &out,
	    "  <LogCategories>\n"
	    "    <Category name=\"logEvents\"\n"
	    "      description=\"springs that break, tunable parameters changed (each restarts the solver), input "
	    "derivatives not used\"/>\n"
	    "    <Category name=\"logStatusWarning\" description=\"calls that return fmi2Warning\"/>\n"
	    "    <Category name=\"logStatusDiscard\"\n"
	    "      description=\"calls that return fmi2Discard: steps the solver could not complete or whose outputs "
	    "overflow, status kinds not delivered\"/>\n"
	    "    <Category name=\"logStatusError\" description=\"calls that return fmi2Error\"/>\n"
	    "    <Category name=\"logSolver\" description=\"integrator statistics after each step\"/>\n"
	    "  </LogCategories>\n");

	char stop[SM_NUMBER_TEXT_CAPACITY], step[SM_NUMBER_TEXT_CAPACITY], tolerance[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(t->stop_time, stop);
	sm_format_number(t->step_size, step);
	sm_format_number(t->tolerance, tolerance);
	fmu_text_appendf(
	    &out, "  <DefaultExperiment startTime=\"0\" stopTime=\"%s\" stepSize=\"%s\" tolerance=\"%s\"/>\n",
	    stop, step, tolerance);

	fmu_text_append_string(&out, "  <ModelVariables>\n");
	for (int32_t i = 0; i < t->count; ++i) {
		const fmu_variable* v = &t->variables[i];
		fmu_text_append_string(&out, "    <ScalarVariable name=\"");
		fmu_text_append_escaped(&out, v->name);
		fmu_text_appendf(&out, "\" valueReference=\"%d\" description=\"", (int)i);
		fmu_text_append_escaped(&out, v->description);
		fmu_text_appendf(&out, "\" causality=\"%s\" variability=\"%s\"", fmu_causality_name(v->causality),
		                 fmu_variability_name(v->variability));
		if (v->causality == FMU_PARAMETER || v->variability == FMU_CONSTANT)
			fmu_text_append_string(&out, " initial=\"exact\"");
		else if (v->causality == FMU_OUTPUT || v->causality == FMU_LOCAL)
			fmu_text_append_string(&out, " initial=\"calculated\"");
		fmu_text_append_string(&out, ">\n      ");
		switch (v->type) {
		case FMU_REAL:
			fmu_text_append_string(&out, "<Real");
			if (v->unit)
				fmu_text_appendf(&out, " unit=\"%s\"", v->unit);
			append_range(&out, v);
			if (v->has_start) {
				char start[SM_NUMBER_TEXT_CAPACITY];
				sm_format_number(v->start_real, start);
				fmu_text_appendf(&out, " start=\"%s\"", start);
			}
			break;
		case FMU_INTEGER:
			fmu_text_append_string(&out, "<Integer");
			append_range(&out, v);
			if (v->has_start)
				fmu_text_appendf(&out, " start=\"%d\"", (int)v->start_integer);
			break;
		case FMU_BOOLEAN:
			fmu_text_append_string(&out, "<Boolean");
			if (v->has_start)
				fmu_text_appendf(&out, " start=\"%s\"", v->start_boolean ? "true" : "false");
			break;
		case FMU_STRING:
			fmu_text_append_string(&out, "<String");
			if (v->has_start) {
				fmu_text_append_string(&out, " start=\"");
				fmu_text_append_escaped(&out, v->start_string);
				fmu_text_append_string(&out, "\"");
			}
			break;
		}
		fmu_text_append_string(&out, "/>\n    </ScalarVariable>\n");
	}
	fmu_text_append_string(&out, "  </ModelVariables>\n");

	int32_t* first = malloc(((size_t)t->port_count + 1) * sizeof *first);
	if (!first)
		out.failed = true;
	for (int32_t i = 0; first && i < t->count; ++i)
		if (t->variables[i].source == FMU_SRC_PORT_POSITION && t->variables[i].component == 0)
			first[t->variables[i].index] = i;
	fmu_text_append_string(&out, "  <ModelStructure>\n    <Outputs>\n");
	for (int32_t i = 0; first && i < t->count; ++i) {
		if (t->variables[i].causality != FMU_OUTPUT)
			continue;
		fmu_text_appendf(&out, "      <Unknown index=\"%d\"", (int)i + 1);
		append_dependencies(&out, t, &t->variables[i], first);
		fmu_text_append_string(&out, "/>\n");
	}
	free(first);
	fmu_text_append_string(&out, "    </Outputs>\n    <InitialUnknowns>\n");
	for (int32_t i = 0; i < t->count; ++i) {
		if (t->variables[i].causality == FMU_OUTPUT)
			fmu_text_appendf(&out, "      <Unknown index=\"%d\"/>\n", (int)i + 1);
	}
	fmu_text_append_string(&out, "    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");

	if (out.failed) {
		free(out.data);
		return NULL;
	}
	return out.data;
}

// ---------------------------------------------------------------------------------------------
// Parameter values set at packaging: resources/parameters.txt
// ---------------------------------------------------------------------------------------------

// Numbers are read and written in the C locale whatever LC_NUMERIC the process chose (an importer
// may run under a decimal comma, where strtod would stop at the '.'): uselocale() switches the
// calling thread only, for the call; glibc's "C" locale object is static (freelocale frees nothing).
typedef struct c_numbers {
	locale_t c;
	locale_t previous;
} c_numbers;

static bool c_numbers_begin(c_numbers* n)
{
	n->c = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
	if (n->c == (locale_t)0)
		return false;
	n->previous = uselocale(n->c);
	return true;
}

static void c_numbers_end(c_numbers* n)
{
	uselocale(n->previous);
	freelocale(n->c);
}

// A line of the file for a message: printable ASCII as it is with '"' and '\\' escaped, any other
// byte as \xNN, cut after QUOTED_LINE_BYTES bytes with "..." (as the model file's messages cut
// their quotes). Each byte takes up to 4 characters, then "..." and the terminating null.
enum { QUOTED_LINE_BYTES = 80, QUOTED_LINE_CAPACITY = 4 * QUOTED_LINE_BYTES + 5 };

static void quote_line(const char* line, size_t length, char* out, size_t size)
{
	size_t k = 0;
	for (size_t i = 0; i < length && i < QUOTED_LINE_BYTES && k + 5 < size; ++i) {
		const unsigned char c = (unsigned char)line[i];
		if (c == '"' || c == '\\')
			k += (size_t)snprintf(out + k, size - k, "\\%c", c);
		else if (c >= 0x20 && c < 0x7f)
			out[k++] = (char)c;
		else
			k += (size_t)snprintf(out + k, size - k, "\\x%02x", c);
	}
	if (length > QUOTED_LINE_BYTES && k + 4 < size) {
		memcpy(out + k, "...", 3);
		k += 3;
	}
	out[k] = '\0';
}

bool fmu_same_parameter_value(double a, double b)
{
	return a == b && signbit(a) == signbit(b);
}

// Writes the line of each parameter of `pending` (count indices) whose value in `set` the model
// takes after those before: one pass in the order given, and with retry, further passes over the
// values refused until a pass takes none. Returns how many are left unwritten; the first refusal's
// message goes to *refusal. Out of memory sets out->failed.
static int32_t write_values(sm_document* file, const sm_document* set, int32_t* pending, int32_t count,
                            bool retry, fmu_text* out, sm_error* refusal)
{
	bool progress = true;
	bool first = true;
	while (count > 0 && progress && !out->failed && (retry || first)) {
		progress = false;
		first = false;
		int32_t kept = 0;
		for (int32_t k = 0; k < count; ++k) {
			const int32_t i = pending[k];
			const double value = sm_document_parameter_value(set, i);
			sm_error e = {SM_OK, ""};
			const sm_status st = sm_document_set_parameter(file, i, value, &e);
			char number[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(value, number);
			if (st == SM_OK) {
				fmu_text_appendf(out, "%s=%s\n", sm_document_parameter_name(file, i), number);
				progress = true;
			} else if (st == SM_ERROR_OUT_OF_MEMORY) {
				out->failed = true;
				break;
			} else {
				if (kept == 0)
					failf(refusal, st, "parameter %s = %s: %s", sm_document_parameter_name(file, i), number,
					      e.message);
				pending[kept++] = i;
			}
		}
		count = kept;
	}
	return count;
}

// Writes the line of each parameter of `pending` (count indices) in that order, unchecked: the
// FMU takes them together (fmu_apply_parameters), as `set`, a valid document, has them. Returns 0.
static int32_t write_together(const sm_document* file, const sm_document* set, const int32_t* pending,
                              int32_t count, fmu_text* out)
{
	for (int32_t k = 0; k < count; ++k) {
		char number[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(sm_document_parameter_value(set, pending[k]), number);
		fmu_text_appendf(out, "%s=%s\n", sm_document_parameter_name(file, pending[k]), number);
	}
	return 0;
}

char* fmu_parameters_text(const sm_document* set, const char* text, size_t length, const char* source_name,
                          const int32_t* order, int32_t order_count, size_t* parameters_length, sm_error* err)
{
	sm_document* file = sm_document_parse(text, length, source_name, err);
	if (!file)
		return NULL;
	const int32_t np = sm_document_parameter_count(set);
	if (np != sm_document_parameter_count(file)) {
		sm_document_destroy(file);
		fail(err, SM_ERROR_INVALID_ARGUMENT, "the document given is not of the model file's text");
		return NULL;
	}
	int32_t* pending = malloc(((size_t)np + 1) * sizeof *pending);
	c_numbers numbers;
	if (!pending || !c_numbers_begin(&numbers)) {
		free(pending);
		sm_document_destroy(file);
		fail(err, SM_ERROR_OUT_OF_MEMORY, "out of memory while writing the parameter values");
		return NULL;
	}
	int32_t count = 0;
	for (int32_t i = 0; i < np; ++i) {
		const double a = sm_document_parameter_value(file, i), b = sm_document_parameter_value(set, i);
		if (!fmu_same_parameter_value(a, b))
			pending[count++] = i;
	}
	// Passes in file order (the same values give the same text, and GUID, whatever order they
	// were given in): each value the model takes is written; one it refuses now is tried again
	// after the others, until all are written or a pass takes none. If some are left, the order
	// the caller set them in, if the model takes it; without one (order NULL), every value in file
	// order, which the FMU takes together (fmu_apply_parameters).
	fmu_text out = {NULL, 0, 0, false};
	fmu_text_append(&out, "", 0);
	sm_error refusal = {SM_OK, ""};
	count = write_values(file, set, pending, count, true, &out, &refusal);
	if (count > 0 && !out.failed) {
		sm_document_destroy(file);
		file = sm_document_parse(text, length, source_name, err);
		out.length = 0;
		if (out.data)
			out.data[0] = '\0';
		count = 0;
		for (int32_t k = 0; k < (order != NULL ? order_count : np) && file && count < np; ++k) {
			const int32_t i = order != NULL ? order[k] : k;
			if (i < 0 || i >= np)
				continue;
			const double a = sm_document_parameter_value(file, i), b = sm_document_parameter_value(set, i);
			if (!fmu_same_parameter_value(a, b))
				pending[count++] = i;
		}
		if (!file)
			out.failed = true;
		else if (order != NULL)
			count = write_values(file, set, pending, count, false, &out, &refusal);
		else
			count = write_together(file, set, pending, count, &out);
	}
	c_numbers_end(&numbers);
	free(pending);
	sm_document_destroy(file);
	if (out.failed) {
		free(out.data);
		fail(err, SM_ERROR_OUT_OF_MEMORY, "out of memory while writing the parameter values");
		return NULL;
	}
	if (count > 0) {
		free(out.data);
		if (err)
			*err = refusal;
		return NULL;
	}
	*parameters_length = out.length;
	return out.data;
}

// Sets err to "source:line: " and the formatted message; returns status.
static sm_status line_error(sm_error* err, sm_status status, const char* source_name, size_t line,
                            const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

static sm_status line_error(sm_error* err, sm_status status, const char* source_name, size_t line,
                            const char* fmt, ...)
{
	char prefix[SM_ERROR_MESSAGE_CAPACITY];
	snprintf(prefix, sizeof prefix, "%s:%zu: ", source_name, line);
	va_list args;
	va_start(args, fmt);
	fail_with(err, status, prefix, fmt, args);
	va_end(args);
	return status;
}

// Applies one line "NAME=VALUE" (line_length bytes, no line feed); first_line[i] is the line that
// set parameter i before (0 for none). The value goes into values[i] too; one the model refuses
// after the lines before, and every one after such a refusal, is left to be taken with all the
// others at the end (values valid only together), the first refusal's message in *refusal.
static sm_status apply_line(sm_document* doc, const char* line, size_t line_length, size_t number,
                            size_t* first_line, double* values, sm_error* refusal, const char* source_name,
                            sm_error* err)
{
	char quoted[QUOTED_LINE_CAPACITY];
	quote_line(line, line_length, quoted, sizeof quoted);
	const char* eq = memchr(line, '=', line_length);
	char name[256], value_text[128];
	const size_t name_length = eq ? (size_t)(eq - line) : 0;
	const size_t value_length = eq ? line_length - name_length - 1 : 0;
	if (!eq || name_length == 0 || memchr(line, '\0', line_length))
		return line_error(err, SM_ERROR_SYNTAX, source_name, number, "expected NAME=VALUE, got \"%s\"",
		                  quoted);
	if (name_length >= sizeof name || value_length >= sizeof value_text)
		return line_error(err, SM_ERROR_SYNTAX, source_name, number,
		                  "\"%s\": the %s is longer than %zu bytes", quoted,
		                  name_length >= sizeof name ? "name" : "value",
		                  (name_length >= sizeof name ? sizeof name : sizeof value_text) - 1);
	memcpy(name, line, name_length);
	name[name_length] = '\0';
	memcpy(value_text, eq + 1, value_length);
	value_text[value_length] = '\0';
	char* end = NULL;
	const double value = strtod(value_text, &end);
	if (value_length == 0 || end != value_text + value_length || !isfinite(value))
		return line_error(err, SM_ERROR_SYNTAX, source_name, number,
		                  "\"%s\": the value is not a finite number", quoted);
	// Only what the packager writes: the shortest of 15, 16 or 17 significant digits that reads
	// back to the value (no sign, space, hexadecimal or trailing zero of its own, and no number
	// that rounds to another).
	char written[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(value, written);
	if (strcmp(written, value_text) != 0)
		return line_error(err, SM_ERROR_SYNTAX, source_name, number,
		                  "\"%s\": the value is not written as the packager writes it (%s)", quoted, written);
	const int32_t index = sm_document_parameter_index(doc, name);
	if (index < 0) {
		char quoted_name[QUOTED_LINE_CAPACITY];
		quote_line(name, name_length, quoted_name, sizeof quoted_name);
		return line_error(err, SM_ERROR_NOT_FOUND, source_name, number,
		                  "\"%s\": the model has no parameter named "
		                  "\"%s\"",
		                  quoted, quoted_name);
	}
	if (first_line[index] != 0)
		return line_error(err, SM_ERROR_SCHEMA, source_name, number,
		                  "parameter %s is set again (first on line %zu)", name, first_line[index]);
	first_line[index] = number;
	values[index] = value;
	if (refusal->status != SM_OK)
		return SM_OK;
	sm_error e = {SM_OK, ""};
	const sm_status st = sm_document_set_parameter(doc, index, value, &e);
	if (st == SM_ERROR_OUT_OF_MEMORY)
		return line_error(err, st, source_name, number, "\"%s\": %s", quoted, e.message);
	if (st != SM_OK)
		line_error(refusal, st, source_name, number, "\"%s\": %s", quoted, e.message);
	return SM_OK;
}

sm_status fmu_apply_parameters(sm_document* doc, const char* parameters, size_t parameters_length,
                               const char* source_name, sm_error* err)
{
	if (!doc || !parameters)
		return fail(err, SM_ERROR_INVALID_ARGUMENT, "no document or no parameter values");
	if (parameters_length == 0)
		return line_error(err, SM_ERROR_SYNTAX, source_name, 1,
		                  "empty: the file lists the parameter values set at "
		                  "packaging, one NAME=VALUE a line, and is left out when there are none");
	const int32_t np = sm_document_parameter_count(doc);
	size_t* first_line = calloc((size_t)np + 1, sizeof *first_line);
	double* values = malloc(((size_t)np + 1) * sizeof *values);
	c_numbers numbers;
	if (!first_line || !values || !c_numbers_begin(&numbers)) {
		free(first_line);
		free(values);
		return fail(err, SM_ERROR_OUT_OF_MEMORY, "out of memory while reading the parameter values");
	}
	for (int32_t i = 0; i < np; ++i)
		values[i] = sm_document_parameter_value(doc, i);
	// The lines one after the other, as the packager writes them where the model takes them so;
	// values that no order takes one at a time (a rope's start and end swapped) are taken together
	// at the end, as `springmass run --set` takes them. A refusal is reported before a malformed
	// line after it, and when the values are refused together too.
	sm_status st = SM_OK;
	sm_error refusal = {SM_OK, ""};
	size_t number = 1;
	for (size_t start = 0; start < parameters_length && st == SM_OK; ++number) {
		const char* feed = memchr(parameters + start, '\n', parameters_length - start);
		const size_t line_length = feed ? (size_t)(feed - (parameters + start)) : parameters_length - start;
		st = apply_line(doc, parameters + start, line_length, number, first_line, values, &refusal,
		                source_name, err);
		start += line_length + 1;
	}
	if (refusal.status != SM_OK && st != SM_ERROR_OUT_OF_MEMORY) {
		sm_error together = {SM_OK, ""};
		st = st == SM_OK ? sm_document_set_parameters(doc, values, &together) : st;
		if (st == SM_ERROR_OUT_OF_MEMORY)
			fail(err, st, together.message);
		else if (st != SM_OK && err)
			*err = refusal;
	}
	c_numbers_end(&numbers);
	free(first_line);
	free(values);
	return st;
}

sm_document* fmu_document_parse(const char* text, size_t length, const char* source_name,
                                const char* parameters, size_t parameters_length, sm_error* err)
{
	sm_document* doc = sm_document_parse(text, length, source_name, err);
	if (doc && parameters &&
	    fmu_apply_parameters(doc, parameters, parameters_length, "resources/" FMU_PARAMETERS_RESOURCE, err) !=
	        SM_OK) {
		sm_document_destroy(doc);
		return NULL;
	}
	return doc;
}

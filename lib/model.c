// The model in memory: creation, validation, particles, springs and accessors.
//
// Every definition is validated field by field before anything is changed, so a failed call
// leaves the model exactly as it was; the message names the particle or spring and the rule.
#include "model_internal.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sm_status sm_model_fail(sm_model* model, sm_status status, const char* format, ...)
{
	if (model != NULL) {
		va_list args;
		va_start(args, format);
		sm_vformat_c_locale(model->last_error, sizeof model->last_error, format, args);
		va_end(args);
	}
	return status;
}

void sm_error_clear(sm_error* err)
{
	if (err != NULL) {
		err->status = SM_OK;
		err->message[0] = '\0';
	}
}

sm_status sm_error_set(sm_error* err, sm_status status, const char* format, ...)
{
	if (err != NULL) {
		err->status = status;
		va_list args;
		va_start(args, format);
		sm_vformat_c_locale(err->message, sizeof err->message, format, args);
		va_end(args);
	}
	return status;
}

void sm_break_strain_floor_text(double break_strain, char text[SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY])
{
	char value[SM_NUMBER_TEXT_CAPACITY], limit[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(break_strain, value);
	sm_format_number(SM_MIN_BREAK_STRAIN, limit);
	snprintf(text, SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY,
	         "break strain = %s must be > 2^-53 = %s: l0 (1 + break strain) would round to l0", value, limit);
}

static bool known_scaling(sm_scaling scaling)
{
	return scaling == SM_ABSOLUTE || scaling == SM_PER_STRAIN || scaling == SM_PER_SECTION;
}

// A spring's own constant (ks [N/m] or kd [N s/m]) from a definition's value (sm_scaling).
static double spring_constant(double value, sm_scaling scaling, double section, double l0)
{
	switch (scaling) {
	case SM_ABSOLUTE: return value;
	case SM_PER_STRAIN: return value / l0;
	case SM_PER_SECTION: return value * section / l0;
	}
	return value;
}

sm_particle_def sm_default_particle_def(void)
{
	sm_particle_def def;
	memset(&def, 0, sizeof def);
	def.mass = 1.0;
	def.motion = SM_PARTICLE_FREE;
	return def;
}

sm_spring_def sm_default_spring_def(void)
{
	sm_spring_def def;
	memset(&def, 0, sizeof def);
	def.a = 0;
	def.b = 0;
	def.kind = SM_SPRING_REST_LENGTH;
	def.rest_length = SM_REST_LENGTH_INITIAL;
	def.stiffness = 0.0;
	def.stiffness_scaling = SM_ABSOLUTE;
	def.damping = 0.0;
	def.damping_scaling = SM_ABSOLUTE;
	def.section = 1.0;
	def.break_strain = INFINITY;
	return def;
}

sm_model_def sm_default_model_def(void)
{
	sm_model_def def;
	memset(&def, 0, sizeof def);
	def.gravity[2] = -9.81;
	def.mass_damping = 0.0;
	return def;
}

// ---------------------------------------------------------------------------------------------
// Validation. Each returns SM_OK or the status of the first rule broken, with the message in
// the buffer (which may be NULL).
// ---------------------------------------------------------------------------------------------

static sm_status say(char* buffer, sm_status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static sm_status say(char* buffer, sm_status status, const char* format, ...)
{
	if (buffer != NULL) {
		va_list args;
		va_start(args, format);
		sm_vformat_c_locale(buffer, SM_ERROR_MESSAGE_CAPACITY, format, args);
		va_end(args);
	}
	return status;
}

static sm_status check_model_def(const sm_model_def* def, char* msg)
{
	if (def == NULL)
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "model definition is NULL");
	static const char axis[3] = {'x', 'y', 'z'};
	for (int k = 0; k < 3; k++)
		if (!isfinite(def->gravity[k]))
			return say(msg, SM_ERROR_NOT_FINITE, "model: gravity %c = %g is not finite", axis[k],
			           def->gravity[k]);
	if (!isfinite(def->mass_damping))
		return say(msg, SM_ERROR_NOT_FINITE, "model: mass damping = %g is not finite", def->mass_damping);
	if (def->mass_damping < 0.0)
		return say(msg, SM_ERROR_NEGATIVE, "model: mass damping = %g must be >= 0", def->mass_damping);
	if (def->particle_capacity < 0)
		return say(msg, SM_ERROR_NEGATIVE, "model: particle capacity = %d must be >= 0",
		           (int)def->particle_capacity);
	if (def->spring_capacity < 0)
		return say(msg, SM_ERROR_NEGATIVE, "model: spring capacity = %d must be >= 0",
		           (int)def->spring_capacity);
	// No room is reserved beyond the most a model holds: such a hint could never be met, whatever
	// the memory.
	const bool particles = def->particle_capacity > SM_MODEL_MAX_ELEMENTS;
	if (particles || def->spring_capacity > SM_MODEL_MAX_ELEMENTS)
		return say(msg, SM_ERROR_INVALID_ARGUMENT,
		           "model: %s capacity = %d exceeds the most %ss a model holds, %d",
		           particles ? "particle" : "spring",
		           (int)(particles ? def->particle_capacity : def->spring_capacity),
		           particles ? "particle" : "spring", SM_MODEL_MAX_ELEMENTS);
	return SM_OK;
}

static sm_status check_particle_def(const sm_particle_def* def, long index, char* msg)
{
	static const char axis[3] = {'x', 'y', 'z'};
	if (def == NULL)
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "particle %ld: definition is NULL", index);
	if (!isfinite(def->mass))
		return say(msg, SM_ERROR_NOT_FINITE, "particle %ld: mass = %g is not finite", index, def->mass);
	if (!(def->mass > 0.0))
		return say(msg, SM_ERROR_NONPOSITIVE_MASS, "particle %ld: mass = %g must be > 0", index, def->mass);
	if (def->mass < SM_MIN_MASS) {
		char value[SM_NUMBER_TEXT_CAPACITY], least[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(def->mass, value);
		sm_format_number(SM_MIN_MASS, least);
		return say(msg, SM_ERROR_NONPOSITIVE_MASS,
		           "particle %ld: mass = %s kg must be at least %s kg, the smallest normal double (1 / mass "
		           "would overflow)",
		           index, value, least);
	}
	for (int k = 0; k < 3; k++)
		if (!isfinite(def->position[k]))
			return say(msg, SM_ERROR_NOT_FINITE, "particle %ld: position %c = %g is not finite", index,
			           axis[k], def->position[k]);
	for (int k = 0; k < 3; k++)
		if (!isfinite(def->velocity[k]))
			return say(msg, SM_ERROR_NOT_FINITE, "particle %ld: velocity %c = %g is not finite", index,
			           axis[k], def->velocity[k]);
	for (int k = 0; k < 3; k++)
		if (!isfinite(def->load[k]))
			return say(msg, SM_ERROR_NOT_FINITE, "particle %ld: load %c = %g N is not finite", index, axis[k],
			           def->load[k]);
	if (def->motion != SM_PARTICLE_FREE && def->motion != SM_PARTICLE_FIXED &&
	    def->motion != SM_PARTICLE_DRIVEN)
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "particle %ld: motion = %d is not a known motion", index,
		           (int)def->motion);
	return SM_OK;
}

// Resolved constants of a valid spring definition.
typedef struct resolved_spring {
	double rest_length;  // [m]
	double stiffness;    // [N/m]
	double damping;      // [N s/m]
} resolved_spring;

// The length of (dx, dy, dz) [m] without the overflow or underflow of its square, for the messages
// of springs too long or too short for that square.
static double distance_of(double dx, double dy, double dz)
{
	return hypot(hypot(dx, dy), dz);
}

// Validates a spring definition against the model; `current_rest_length` is used for
// SM_REST_LENGTH_INITIAL when >= 0 (sm_model_set_spring keeps the current rest length),
// otherwise the distance between the particles' initial positions. *out is zero unless the
// definition is valid (so that no caller reads it unset, whatever a compiler sees of the paths).
static sm_status check_spring_def(const sm_model* model, const sm_spring_def* def, long index,
                                  double current_rest_length, resolved_spring* out, char* msg)
{
	*out = (resolved_spring){0};
	if (def == NULL)
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "spring %ld: definition is NULL", index);
	const long n = model->particle_count;
	if (def->a < 0 || def->a >= n)
		return say(msg, SM_ERROR_PARTICLE_INDEX,
		           "spring %ld: particle a = %ld out of range (model has %ld particle%s)", index,
		           (long)def->a, n, n == 1 ? "" : "s");
	if (def->b < 0 || def->b >= n)
		return say(msg, SM_ERROR_PARTICLE_INDEX,
		           "spring %ld: particle b = %ld out of range (model has %ld particle%s)", index,
		           (long)def->b, n, n == 1 ? "" : "s");
	if (def->a == def->b)
		return say(msg, SM_ERROR_SELF_SPRING, "spring %ld: connects particle %ld to itself (a = b)", index,
		           (long)def->a);
	if (def->kind != SM_SPRING_REST_LENGTH && def->kind != SM_SPRING_ZERO_LENGTH)
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "spring %ld: kind = %d is not a known spring kind", index,
		           (int)def->kind);
	if (!known_scaling(def->stiffness_scaling))
		return say(msg, SM_ERROR_INVALID_ARGUMENT,
		           "spring %ld: stiffness scaling = %d is not a known scaling", index,
		           (int)def->stiffness_scaling);
	if (!known_scaling(def->damping_scaling))
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "spring %ld: damping scaling = %d is not a known scaling",
		           index, (int)def->damping_scaling);
	if ((def->stiffness_scaling == SM_PER_SECTION || def->damping_scaling == SM_PER_SECTION) &&
	    !(isfinite(def->section) && def->section > 0.0))
		return say(msg, isfinite(def->section) ? SM_ERROR_NEGATIVE : SM_ERROR_NOT_FINITE,
		           "spring %ld: section = %g must be finite and > 0 for per-section constants", index,
		           def->section);
	if (!isfinite(def->stiffness))
		return say(msg, SM_ERROR_NOT_FINITE, "spring %ld: stiffness = %g is not finite", index,
		           def->stiffness);
	if (def->stiffness < 0.0)
		return say(msg, SM_ERROR_NEGATIVE, "spring %ld: stiffness = %g must be >= 0", index, def->stiffness);
	if (!isfinite(def->damping))
		return say(msg, SM_ERROR_NOT_FINITE, "spring %ld: damping = %g is not finite", index, def->damping);
	if (def->damping < 0.0)
		return say(msg, SM_ERROR_NEGATIVE, "spring %ld: damping = %g must be >= 0", index, def->damping);
	if (isnan(def->break_strain) || def->break_strain == -INFINITY)
		return say(msg, SM_ERROR_NOT_FINITE,
		           "spring %ld: break strain = %g must be a number > 0, or INFINITY for never", index,
		           def->break_strain);
	if (!(def->break_strain > 0.0))
		return say(msg, SM_ERROR_NEGATIVE, "spring %ld: break strain = %g must be > 0 (INFINITY for never)",
		           index, def->break_strain);
	if (!(def->break_strain > SM_MIN_BREAK_STRAIN)) {
		char rule[SM_BREAK_STRAIN_FLOOR_TEXT_CAPACITY];
		sm_break_strain_floor_text(def->break_strain, rule);
		return say(msg, SM_ERROR_INVALID_ARGUMENT, "spring %ld: %s, and the spring would break at rest",
		           index, rule);
	}

	// Rest length. A spring's length must be a double, whatever its kind and rest length: its square
	// may not overflow. Both kinds are evaluated from L and u = d / L (law_zero_length.h), which
	// give ks (L - 0) u = inf 0, not a number, where L overflows.
	const double* xa = model->position + 3 * (size_t)def->a;
	const double* xb = model->position + 3 * (size_t)def->b;
	const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
	const double squared = dx * dx + dy * dy + dz * dz;
	if (!isfinite(sqrt(squared))) {
		const double distance = distance_of(dx, dy, dz);
		char shown[32] = "more than 1.8e+308";
		if (isfinite(distance))
			snprintf(shown, sizeof shown, "%.3g", distance);
		return say(msg, SM_ERROR_NOT_FINITE,
		           "spring %ld: the initial distance between particles %ld and %ld, %s m, is too large (its "
		           "square overflows: particles joined by springs must be less than 1.3e154 m apart)",
		           index, (long)def->a, (long)def->b, shown);
	}
	double l0;
	if (def->rest_length == SM_REST_LENGTH_INITIAL) {
		if (def->kind == SM_SPRING_ZERO_LENGTH) {
			l0 = 0.0;
		} else if (current_rest_length >= 0.0) {
			l0 = current_rest_length;
		} else {
			l0 = sqrt(squared);
			// A square below DBL_MIN has lost digits or all of them (1e-170 m gives l0 = 0): the
			// rest length would not be the distance. Structures refuse such springs too; particles
			// at one point keep l0 = 0.
			if (squared < DBL_MIN && (dx != 0.0 || dy != 0.0 || dz != 0.0))
				return say(
				    msg, SM_ERROR_INVALID_ARGUMENT,
				    "spring %ld: the initial distance between particles %ld and %ld, %.3g m, is too small (its "
				    "square underflows: particles joined by springs must be at one point or more than about "
				    "1.5e-154 m apart)",
				    index, (long)def->a, (long)def->b, distance_of(dx, dy, dz));
		}
	} else {
		l0 = def->rest_length;
		if (!isfinite(l0))
			return say(msg, SM_ERROR_NOT_FINITE, "spring %ld: rest length = %g is not finite", index, l0);
		if (l0 < 0.0)
			return say(msg, SM_ERROR_NEGATIVE,
			           "spring %ld: rest length = %g must be >= 0 (or SM_REST_LENGTH_INITIAL)", index, l0);
		if (def->kind == SM_SPRING_ZERO_LENGTH && l0 != 0.0)
			return say(msg, SM_ERROR_INVALID_ARGUMENT,
			           "spring %ld: a zero-length spring must have rest length 0, not %g", index, l0);
	}
	if (def->stiffness_scaling != SM_ABSOLUTE && !(l0 > 0.0))
		return say(msg, SM_ERROR_ZERO_REST_LENGTH,
		           "spring %ld: per-%s stiffness needs a rest length > 0 (rest length is %g)", index,
		           def->stiffness_scaling == SM_PER_STRAIN ? "strain" : "section", l0);
	if (def->damping_scaling != SM_ABSOLUTE && !(l0 > 0.0))
		return say(msg, SM_ERROR_ZERO_REST_LENGTH,
		           "spring %ld: per-%s damping needs a rest length > 0 (rest length is %g)", index,
		           def->damping_scaling == SM_PER_STRAIN ? "strain" : "section", l0);
	if (isfinite(def->break_strain) && !(l0 > 0.0))
		return say(msg, SM_ERROR_ZERO_REST_LENGTH,
		           "spring %ld: a break strain needs a rest length > 0 (rest length is %g)", index, l0);

	const double ks = spring_constant(def->stiffness, def->stiffness_scaling, def->section, l0);
	const double kd = spring_constant(def->damping, def->damping_scaling, def->section, l0);
	if (!isfinite(ks))
		return def->stiffness_scaling == SM_PER_SECTION
		           ? say(msg, SM_ERROR_NOT_FINITE,
				         "spring %ld: stiffness x section / l0 = %g x %g / %g is not finite", index,
				         def->stiffness, def->section, l0)
				   : say(msg, SM_ERROR_NOT_FINITE, "spring %ld: stiffness E / l0 = %g / %g is not finite",
				         index, def->stiffness, l0);
	if (!isfinite(kd))
		return def->damping_scaling == SM_PER_SECTION
		           ? say(msg, SM_ERROR_NOT_FINITE,
				         "spring %ld: damping x section / l0 = %g x %g / %g is not finite", index,
				         def->damping, def->section, l0)
				   : say(msg, SM_ERROR_NOT_FINITE, "spring %ld: damping c / l0 = %g / %g is not finite",
				         index, def->damping, l0);
	out->rest_length = l0;
	out->stiffness = ks;
	out->damping = kd;
	return SM_OK;
}

// ---------------------------------------------------------------------------------------------
// Storage.
// ---------------------------------------------------------------------------------------------

static void free_arrays(sm_model* m)
{
	free(m->mass);
	free(m->position);
	free(m->velocity);
	free(m->motion);
	free(m->load);
	free(m->free_index);
	free(m->spring_def);
	free(m->spring_a);
	free(m->spring_b);
	free(m->rest_length);
	free(m->stiffness);
	free(m->damping);
	free(m->zero_length);
	free(m->enabled);
}

// Reallocates `array`, a pointer of any type, to `count` elements, by way of the caller's void*
// `spare`; false, with the array as it was, when memory runs out. The array is assigned as its own
// type: written through a void** it would break C's aliasing rules.
#define GROW(array, count, spare)                                                                            \
	(((spare) = realloc((array), (count) * sizeof *(array))) != NULL && ((array) = (spare), true))

// Ensures room for `needed` particles. Arrays that already grew keep their larger size (their
// contents are intact), so a failure changes nothing observable.
static int reserve_particles(sm_model* m, int64_t needed)
{
	if (needed <= m->particle_capacity)
		return 1;
	if (needed > SM_MODEL_MAX_ELEMENTS)
		return 0;
	int64_t cap = m->particle_capacity > 0 ? m->particle_capacity : 16;
	while (cap < needed)
		cap *= 2;
	if (cap > SM_MODEL_MAX_ELEMENTS)
		cap = SM_MODEL_MAX_ELEMENTS;
	const size_t c = (size_t)cap;
	void* spare;
	if (!GROW(m->mass, c, spare) || !GROW(m->position, 3 * c, spare) || !GROW(m->velocity, 3 * c, spare) ||
	    !GROW(m->motion, c, spare) || !GROW(m->load, 3 * c, spare) || !GROW(m->free_index, c, spare))
		return 0;
	m->particle_capacity = (int32_t)cap;
	return 1;
}

static int reserve_springs(sm_model* m, int64_t needed)
{
	if (needed <= m->spring_capacity)
		return 1;
	if (needed > SM_MODEL_MAX_ELEMENTS)
		return 0;
	int64_t cap = m->spring_capacity > 0 ? m->spring_capacity : 16;
	while (cap < needed)
		cap *= 2;
	if (cap > SM_MODEL_MAX_ELEMENTS)
		cap = SM_MODEL_MAX_ELEMENTS;
	const size_t c = (size_t)cap;
	void* spare;
	if (!GROW(m->spring_def, c, spare) || !GROW(m->spring_a, c, spare) || !GROW(m->spring_b, c, spare) ||
	    !GROW(m->rest_length, c, spare) || !GROW(m->stiffness, c, spare) || !GROW(m->damping, c, spare) ||
	    !GROW(m->zero_length, c, spare) || !GROW(m->enabled, c, spare))
		return 0;
	m->spring_capacity = (int32_t)cap;
	return 1;
}

static void renumber_free(sm_model* m)
{
	int32_t count = 0;
	for (int32_t i = 0; i < m->particle_count; i++)
		m->free_index[i] = m->motion[i] == SM_PARTICLE_FREE ? count++ : -1;
	m->free_count = count;
}

sm_model* sm_model_create(const sm_model_def* def, sm_error* err)
{
	char msg[SM_ERROR_MESSAGE_CAPACITY];
	sm_status st = check_model_def(def, msg);
	if (st != SM_OK) {
		sm_error_set(err, st, "%s", msg);
		return NULL;
	}
	sm_model* m = calloc(1, sizeof *m);
	if (m == NULL) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "model: out of memory");
		return NULL;
	}
	m->def = *def;
	if (!reserve_particles(m, def->particle_capacity) || !reserve_springs(m, def->spring_capacity)) {
		sm_model_destroy(m);
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		             "model: out of memory reserving %d particles and %d springs",
		             (int)def->particle_capacity, (int)def->spring_capacity);
		return NULL;
	}
	sm_error_set(err, SM_OK, "%s", "");
	return m;
}

void sm_model_destroy(sm_model* model)
{
	if (model == NULL)
		return;
	free_arrays(model);
	free(model);
}

static void* duplicate(const void* source, size_t bytes, int* ok)
{
	if (bytes == 0 || source == NULL)
		return NULL;
	void* p = malloc(bytes);
	if (p == NULL) {
		*ok = 0;
		return NULL;
	}
	memcpy(p, source, bytes);
	return p;
}

sm_model* sm_model_clone(const sm_model* model)
{
	if (model == NULL)
		return NULL;
	sm_model* m = calloc(1, sizeof *m);
	if (m == NULL)
		return NULL;
	*m = *model;
	m->last_error[0] = '\0';  // the copy has had no failed call
	const size_t pc = (size_t)model->particle_capacity, sc = (size_t)model->spring_capacity;
	int ok = 1;
	m->mass = duplicate(model->mass, pc * sizeof(double), &ok);
	m->position = duplicate(model->position, 3 * pc * sizeof(double), &ok);
	m->velocity = duplicate(model->velocity, 3 * pc * sizeof(double), &ok);
	m->motion = duplicate(model->motion, pc * sizeof(sm_particle_motion), &ok);
	m->load = duplicate(model->load, 3 * pc * sizeof(double), &ok);
	m->free_index = duplicate(model->free_index, pc * sizeof(int32_t), &ok);
	m->spring_def = duplicate(model->spring_def, sc * sizeof(sm_spring_def), &ok);
	m->spring_a = duplicate(model->spring_a, sc * sizeof(int32_t), &ok);
	m->spring_b = duplicate(model->spring_b, sc * sizeof(int32_t), &ok);
	m->rest_length = duplicate(model->rest_length, sc * sizeof(double), &ok);
	m->stiffness = duplicate(model->stiffness, sc * sizeof(double), &ok);
	m->damping = duplicate(model->damping, sc * sizeof(double), &ok);
	m->zero_length = duplicate(model->zero_length, sc * sizeof(uint8_t), &ok);
	m->enabled = duplicate(model->enabled, sc * sizeof(uint8_t), &ok);
	if (!ok) {
		sm_model_destroy(m);
		return NULL;
	}
	return m;
}

const char* sm_model_last_error(const sm_model* model)
{
	return model != NULL ? model->last_error : "model is NULL";
}

// ---------------------------------------------------------------------------------------------
// Particles.
// ---------------------------------------------------------------------------------------------

static bool loaded(const double load[3])
{
	return load[0] != 0.0 || load[1] != 0.0 || load[2] != 0.0;
}

// Stores particle i's definition; its place holds no load before (a new particle), or had its
// load taken out of load_count.
static void store_particle(sm_model* m, int32_t i, const sm_particle_def* def)
{
	m->mass[i] = def->mass;
	memcpy(m->load + 3 * (size_t)i, def->load, 3 * sizeof(double));
	m->load_count += loaded(def->load);
	for (int k = 0; k < 3; k++) {
		m->position[3 * (size_t)i + k] = def->position[k];
		// A fixed particle does not move: its stored velocity is zero whatever was given.
		m->velocity[3 * (size_t)i + k] = def->motion == SM_PARTICLE_FIXED ? 0.0 : def->velocity[k];
	}
	m->motion[i] = def->motion;
}

sm_status sm_model_add_particle(sm_model* model, const sm_particle_def* def, int32_t* index)
{
	if (index != NULL)
		*index = -1;
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	model->last_error[0] = '\0';
	sm_status st = check_particle_def(def, (long)model->particle_count, model->last_error);
	if (st != SM_OK)
		return st;
	if (model->particle_count >= SM_MODEL_MAX_ELEMENTS ||
	    !reserve_particles(model, (int64_t)model->particle_count + 1))
		return sm_model_fail(model, SM_ERROR_OUT_OF_MEMORY, "particle %ld: out of memory",
		                     (long)model->particle_count);
	const int32_t i = model->particle_count++;
	store_particle(model, i, def);
	model->free_index[i] = def->motion == SM_PARTICLE_FREE ? model->free_count++ : -1;
	if (index != NULL)
		*index = i;
	return SM_OK;
}

int32_t sm_model_particle_count(const sm_model* model)
{
	return model != NULL ? model->particle_count : 0;
}

int32_t sm_model_spring_count(const sm_model* model)
{
	return model != NULL ? model->spring_count : 0;
}

static sm_status check_particle_index(sm_model* model, int32_t index)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (index < 0 || index >= model->particle_count)
		return sm_model_fail(model, SM_ERROR_PARTICLE_INDEX,
		                     "particle %ld out of range (model has %ld particle%s)", (long)index,
		                     (long)model->particle_count, model->particle_count == 1 ? "" : "s");
	return SM_OK;
}

sm_status sm_model_get_particle(const sm_model* model, int32_t index, sm_particle_def* def)
{
	if (def != NULL)
		*def = (sm_particle_def){0};
	if (model == NULL || def == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (index < 0 || index >= model->particle_count)
		return SM_ERROR_PARTICLE_INDEX;
	def->mass = model->mass[index];
	for (int k = 0; k < 3; k++) {
		def->position[k] = model->position[3 * (size_t)index + k];
		def->velocity[k] = model->velocity[3 * (size_t)index + k];
	}
	def->motion = model->motion[index];
	memcpy(def->load, model->load + 3 * (size_t)index, 3 * sizeof(double));
	return SM_OK;
}

sm_status sm_model_set_particle(sm_model* model, int32_t index, const sm_particle_def* def)
{
	sm_status st = check_particle_index(model, index);
	if (st != SM_OK)
		return st;
	model->last_error[0] = '\0';
	st = check_particle_def(def, (long)index, model->last_error);
	if (st != SM_OK)
		return st;
	const int renumber = def->motion != model->motion[index];
	model->load_count -= loaded(model->load + 3 * (size_t)index);
	store_particle(model, index, def);
	if (renumber)
		renumber_free(model);
	return SM_OK;
}

static void store_motion(sm_model* m, int32_t i, sm_particle_motion motion)
{
	m->motion[i] = motion;
	if (motion == SM_PARTICLE_FIXED)
		memset(m->velocity + 3 * (size_t)i, 0, 3 * sizeof(double));
}

void sm_model_set_motions(sm_model* m, const bool* select, const int32_t* particles, int32_t count,
                          sm_particle_motion motion)
{
	if (select != NULL) {
		for (int32_t i = 0; i < m->particle_count; i++)
			if (select[i])
				store_motion(m, i, motion);
	} else {
		for (int32_t k = 0; k < count; k++)
			store_motion(m, particles[k], motion);
	}
	renumber_free(m);
}

sm_status sm_model_set_particle_motion(sm_model* model, int32_t index, sm_particle_motion motion)
{
	sm_status st = check_particle_index(model, index);
	if (st != SM_OK)
		return st;
	sm_particle_def def;
	sm_model_get_particle(model, index, &def);
	def.motion = motion;
	return sm_model_set_particle(model, index, &def);
}

// ---------------------------------------------------------------------------------------------
// Springs.
// ---------------------------------------------------------------------------------------------

static void store_spring(sm_model* m, int32_t s, const sm_spring_def* def, const resolved_spring* r)
{
	m->spring_def[s] = *def;
	m->spring_def[s].rest_length = r->rest_length;
	m->spring_a[s] = def->a;
	m->spring_b[s] = def->b;
	m->rest_length[s] = r->rest_length;
	m->zero_length[s] = def->kind == SM_SPRING_ZERO_LENGTH;
	m->stiffness[s] = m->enabled[s] ? r->stiffness : 0.0;
	m->damping[s] = m->enabled[s] ? r->damping : 0.0;
}

sm_status sm_model_add_spring(sm_model* model, const sm_spring_def* def, int32_t* index)
{
	if (index != NULL)
		*index = -1;
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	model->last_error[0] = '\0';
	resolved_spring r;
	sm_status st = check_spring_def(model, def, (long)model->spring_count, -1.0, &r, model->last_error);
	if (st != SM_OK)
		return st;
	if (model->spring_count >= SM_MODEL_MAX_ELEMENTS ||
	    !reserve_springs(model, (int64_t)model->spring_count + 1))
		return sm_model_fail(model, SM_ERROR_OUT_OF_MEMORY, "spring %ld: out of memory",
		                     (long)model->spring_count);
	const int32_t s = model->spring_count++;
	model->enabled[s] = 1;
	store_spring(model, s, def, &r);
	if (index != NULL)
		*index = s;
	return SM_OK;
}

static sm_status check_spring_index(sm_model* model, int32_t index)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (index < 0 || index >= model->spring_count)
		return sm_model_fail(model, SM_ERROR_SPRING_INDEX, "spring %ld out of range (model has %ld spring%s)",
		                     (long)index, (long)model->spring_count, model->spring_count == 1 ? "" : "s");
	return SM_OK;
}

sm_status sm_model_get_spring(const sm_model* model, int32_t index, sm_spring_def* def)
{
	if (def != NULL)
		*def = (sm_spring_def){0};
	if (model == NULL || def == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (index < 0 || index >= model->spring_count)
		return SM_ERROR_SPRING_INDEX;
	*def = model->spring_def[index];
	return SM_OK;
}

sm_status sm_model_set_spring(sm_model* model, int32_t index, const sm_spring_def* def)
{
	sm_status st = check_spring_index(model, index);
	if (st != SM_OK)
		return st;
	model->last_error[0] = '\0';
	resolved_spring r;
	st = check_spring_def(model, def, (long)index, model->rest_length[index], &r, model->last_error);
	if (st != SM_OK)
		return st;
	store_spring(model, index, def, &r);
	return SM_OK;
}

sm_status sm_model_spring_constants(const sm_model* model, int32_t index, double* rest_length,
                                    double* stiffness, double* damping)
{
	double* const outputs[3] = {rest_length, stiffness, damping};
	for (int k = 0; k < 3; k++)
		if (outputs[k] != NULL)
			*outputs[k] = 0.0;
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (index < 0 || index >= model->spring_count)
		return SM_ERROR_SPRING_INDEX;
	const sm_spring_def* d = &model->spring_def[index];
	const double l0 = model->rest_length[index];
	// The constants of the definition, also while the spring is disabled.
	if (rest_length != NULL)
		*rest_length = l0;
	if (stiffness != NULL)
		*stiffness = spring_constant(d->stiffness, d->stiffness_scaling, d->section, l0);
	if (damping != NULL)
		*damping = spring_constant(d->damping, d->damping_scaling, d->section, l0);
	return SM_OK;
}

sm_status sm_model_set_spring_enabled(sm_model* model, int32_t index, bool enabled)
{
	sm_status st = check_spring_index(model, index);
	if (st != SM_OK)
		return st;
	model->last_error[0] = '\0';
	model->enabled[index] = enabled ? 1 : 0;
	// The hot arrays hold zero constants while disabled, so the force loop needs no branch; the
	// stored definition restores them.
	double ks = 0.0, kd = 0.0;
	if (enabled)
		sm_model_spring_constants(model, index, NULL, &ks, &kd);
	model->stiffness[index] = ks;
	model->damping[index] = kd;
	return SM_OK;
}

bool sm_model_spring_enabled(const sm_model* model, int32_t index)
{
	if (model == NULL || index < 0 || index >= model->spring_count)
		return false;
	return model->enabled[index] != 0;
}

// ---------------------------------------------------------------------------------------------
// Global settings and accessors.
// ---------------------------------------------------------------------------------------------

sm_model_def sm_model_get_def(const sm_model* model)
{
	if (model == NULL)
		return sm_default_model_def();
	sm_model_def def = model->def;
	def.particle_capacity = model->particle_capacity;
	def.spring_capacity = model->spring_capacity;
	return def;
}

sm_status sm_model_set_def(sm_model* model, const sm_model_def* def)
{
	if (model == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	model->last_error[0] = '\0';
	sm_status st = check_model_def(def, model->last_error);
	if (st != SM_OK)
		return st;
	for (int k = 0; k < 3; k++)
		model->def.gravity[k] = def->gravity[k];
	model->def.mass_damping = def->mass_damping;
	return SM_OK;
}

void sm_model_initial_state(const sm_model* model, double* x, double* v)
{
	if (model == NULL)
		return;
	const size_t n = 3 * (size_t)model->particle_count;
	if (x != NULL && n > 0)
		memcpy(x, model->position, n * sizeof(double));
	if (v != NULL && n > 0)
		memcpy(v, model->velocity, n * sizeof(double));
}

double sm_model_total_mass(const sm_model* model)
{
	if (model == NULL)
		return 0.0;
	double total = 0.0;
	for (int32_t i = 0; i < model->particle_count; i++)
		total += model->mass[i];
	return total;
}

int32_t sm_model_free_count(const sm_model* model)
{
	return model != NULL ? model->free_count : 0;
}

int32_t sm_model_free_index(const sm_model* model, int32_t particle)
{
	if (model == NULL || particle < 0 || particle >= model->particle_count)
		return -1;
	return model->free_index[particle];
}

// libFuzzer target for the model-file loader: any input must either be refused with a message
// or load; a loaded document must build, and its canonical form must load again to the same model,
// bit for bit (every particle's mass, position, velocity, load and motion, every spring's ends,
// law and constants, the ports, the settings and the parameters it keeps), and save to the same
// text again (the writer and the loader agree on every file the loader accepts).
#include "model_file_internal.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Models larger than this are refused early: the fuzzer looks for wrong handling of input,
// not for the time it takes to build a cloth of millions of particles.
#define FUZZ_MAX_ELEMENTS 20000

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

// The same double, down to the sign of a zero.
static bool same(double a, double b)
{
	return memcmp(&a, &b, sizeof a) == 0;
}

static void differ(const char* what, long index)
{
	fprintf(stderr, "the canonical form loads to another model: %s (%ld)\n", what, index);
	abort();
}

// The reloaded document (d2, built into m2) is the original (d1, built into m1).
static void compare(const sm_document* d1, const sm_model* m1, const sm_document* d2, const sm_model* m2)
{
	if (strcmp(sm_document_name(d1), sm_document_name(d2)) != 0 ||
	    strcmp(sm_document_description(d1), sm_document_description(d2)) != 0)
		differ("name or description", 0);
	const sm_model_def a = sm_model_get_def(m1), b = sm_model_get_def(m2);
	if (!same(a.gravity[0], b.gravity[0]) || !same(a.gravity[1], b.gravity[1]) ||
	    !same(a.gravity[2], b.gravity[2]) || !same(a.mass_damping, b.mass_damping))
		differ("gravity or mass damping", 0);
	const int32_t n = sm_model_particle_count(m1);
	if (n != sm_model_particle_count(m2))
		differ("particle count", n);
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def p, q;
		sm_model_get_particle(m1, i, &p);
		sm_model_get_particle(m2, i, &q);
		bool equal = same(p.mass, q.mass) && p.motion == q.motion;
		for (int c = 0; c < 3; c++)
			equal = equal && same(p.position[c], q.position[c]) && same(p.velocity[c], q.velocity[c]) &&
			        same(p.load[c], q.load[c]);
		const char* n1 = sm_document_particle_name(d1, i);
		const char* n2 = sm_document_particle_name(d2, i);
		if (!equal || (n1 == NULL) != (n2 == NULL) || (n1 != NULL && strcmp(n1, n2) != 0))
			differ("particle", i);
	}
	const int32_t m = sm_model_spring_count(m1);
	if (m != sm_model_spring_count(m2))
		differ("spring count", m);
	for (int32_t s = 0; s < m; s++) {
		sm_spring_def p, q;
		sm_model_get_spring(m1, s, &p);
		sm_model_get_spring(m2, s, &q);
		double k1[3], k2[3];
		sm_model_spring_constants(m1, s, &k1[0], &k1[1], &k1[2]);
		sm_model_spring_constants(m2, s, &k2[0], &k2[1], &k2[2]);
		if (p.a != q.a || p.b != q.b || p.kind != q.kind || !same(p.break_strain, q.break_strain) ||
		    !same(k1[0], k2[0]) || !same(k1[1], k2[1]) || !same(k1[2], k2[2]))
			differ("spring", s);
	}
	const int32_t ports = sm_document_port_count(d1);
	if (ports != sm_document_port_count(d2))
		differ("port count", ports);
	for (int32_t k = 0; k < ports; k++) {
		const sm_port p = sm_document_port(d1, k), q = sm_document_port(d2, k);
		if (strcmp(p.name, q.name) != 0 || p.particle != q.particle || p.kind != q.kind)
			differ("port", k);
	}
	const sm_document_settings e = sm_document_get_settings(d1), f = sm_document_get_settings(d2);
	if (!same(e.stop_time, f.stop_time) || !same(e.output_interval, f.output_interval) ||
	    e.particle_variables != f.particle_variables || e.solver.method != f.solver.method ||
	    e.solver.solver != f.solver.solver || e.solver.jacobian != f.solver.jacobian ||
	    !same(e.solver.relative_tolerance, f.solver.relative_tolerance) ||
	    !same(e.solver.absolute_tolerance_position, f.solver.absolute_tolerance_position) ||
	    !same(e.solver.absolute_tolerance_velocity, f.solver.absolute_tolerance_velocity) ||
	    !same(e.solver.max_step, f.solver.max_step) || e.solver.max_steps != f.solver.max_steps ||
	    e.solver.restart_on_input_change != f.solver.restart_on_input_change ||
	    e.solver.stability_limit_detection != f.solver.stability_limit_detection)
		differ("settings", 0);
	// The parameters kept are the file's, with their values, feed no more than they did and keep
	// the unit they had (one of several may become the only one).
	for (int32_t j = 0; j < sm_document_parameter_count(d2); j++) {
		const int32_t i = sm_document_parameter_index(d1, sm_document_parameter_name(d2, j));
		if (i < 0 || !same(sm_document_parameter_value(d1, i), sm_document_parameter_value(d2, j)) ||
		    (sm_document_parameter_uses(d2, j) & ~sm_document_parameter_uses(d1, i)) != 0 ||
		    (sm_document_parameter_unit(d1, i)[0] != '\0' &&
		     strcmp(sm_document_parameter_unit(d1, i), sm_document_parameter_unit(d2, j)) != 0))
			differ("parameter", j);
	}
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    sm_document_parse_limited((const char*)data, size, "fuzz.json", FUZZ_MAX_ELEMENTS, &err);
	if (doc == NULL) {
		if (err.status == SM_OK || err.message[0] == '\0')
			abort();  // a refusal must say why
		return 0;
	}
	sm_model* model = NULL;
	if (sm_document_build(doc, &model, &err) != SM_OK)
		abort();
	char* text = sm_document_to_json(doc, &err);
	if (text == NULL)
		abort();
	sm_document* again = sm_document_parse_limited(text, strlen(text), "saved.json", FUZZ_MAX_ELEMENTS, &err);
	if (again == NULL) {
		fprintf(stderr, "canonical form does not load: %s\n", err.message);
		abort();
	}
	sm_model* rebuilt = NULL;
	if (sm_document_build(again, &rebuilt, &err) != SM_OK)
		abort();
	compare(doc, model, again, rebuilt);
	char* text_again = sm_document_to_json(again, &err);
	if (text_again == NULL || strcmp(text, text_again) != 0)
		abort();  // saving the saved file changes it
	free(text_again);
	// Changing a parameter either works or is refused with the document unchanged.
	if (sm_document_parameter_count(doc) > 0) {
		const double before = sm_document_parameter_value(doc, 0);
		if (sm_document_set_parameter(doc, 0, before * 2.0 + 1.0, &err) != SM_OK &&
		    sm_document_parameter_value(doc, 0) != before)
			abort();
	}
	sm_model_destroy(rebuilt);
	sm_model_destroy(model);
	sm_document_destroy(again);
	free(text);
	sm_document_destroy(doc);
	return 0;
}

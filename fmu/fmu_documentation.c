// springmass FMU: documentation/index.html, the page an importing tool shows for the FMU
// (FMI 2.0, "FMU distribution": documentation/index.html is the documentation's entry point and
// documentation/licenses/license.txt the licences'). Written from the same variable table as
// modelDescription.xml, so that the page and the FMU cannot disagree.
#include "fmu_model.h"
#include "fmu_text.h"

#include "springmass/base.h"

#include <stdlib.h>

static void append_start(fmu_text* out, const fmu_variable* v)
{
	if (!v->has_start)
		return;
	switch (v->type) {
	case FMU_REAL: {
		char number[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(v->start_real, number);
		fmu_text_append_string(out, number);
		break;
	}
	case FMU_INTEGER: fmu_text_appendf(out, "%d", (int)v->start_integer); break;
	case FMU_BOOLEAN: fmu_text_append_string(out, v->start_boolean ? "true" : "false"); break;
	case FMU_STRING: fmu_text_append_escaped(out, v->start_string); break;
	}
}

static bool is_particle_state(const fmu_variable* v)
{
	return v->source == FMU_SRC_PARTICLE_POSITION || v->source == FMU_SRC_PARTICLE_VELOCITY;
}

// Which rows a table holds.
typedef enum section {
	SECTION_INPUTS,
	SECTION_OUTPUTS,
	SECTION_PARAMETERS,
	SECTION_CONSTANTS,
} section;

static bool in_section(const fmu_variable* v, section s)
{
	switch (s) {
	case SECTION_INPUTS: return v->causality == FMU_INPUT;
	case SECTION_OUTPUTS: return v->causality == FMU_OUTPUT;
	case SECTION_PARAMETERS: return v->causality == FMU_PARAMETER;
	case SECTION_CONSTANTS: return v->causality == FMU_LOCAL && v->variability == FMU_CONSTANT;
	}
	return false;
}

// One table: value reference, name, variability (parameters only), unit, start value (not for
// outputs, which have none) and description of every variable of the section; nothing when the
// section is empty.
static void append_table(fmu_text* out, const fmu_table* t, section s, const char* heading, const char* intro)
{
	int32_t rows = 0;
	for (int32_t i = 0; i < t->count; ++i)
		rows += in_section(&t->variables[i], s);
	if (rows == 0)
		return;
	const bool variability = s == SECTION_PARAMETERS, start = s != SECTION_OUTPUTS;
	fmu_text_appendf(out,
	                 "<h2 id=\"%s\">%s</h2>\n<p>%s</p>\n<table>\n<tr><th>value reference</th><th>name</th>",
	                 heading, heading, intro);
	if (variability)
		fmu_text_append_string(out, "<th>variability</th>");
	fmu_text_append_string(out, "<th>unit</th>");
	if (start)
		fmu_text_appendf(out, "<th>%s</th>", s == SECTION_CONSTANTS ? "value" : "start");
	fmu_text_append_string(out, "<th>description</th></tr>\n");
	for (int32_t i = 0; i < t->count; ++i) {
		const fmu_variable* v = &t->variables[i];
		if (!in_section(v, s))
			continue;
		fmu_text_appendf(out, "<tr><td>%d</td><td><code>", (int)i);
		fmu_text_append_escaped(out, v->name);
		fmu_text_append_string(out, "</code></td>");
		if (variability)
			fmu_text_appendf(out, "<td>%s</td>", fmu_variability_name(v->variability));
		fmu_text_append_string(out, "<td>");
		fmu_text_append_escaped(out, v->unit);
		if (start) {
			fmu_text_append_string(out, "</td><td>");
			append_start(out, v);
		}
		fmu_text_append_string(out, "</td><td>");
		fmu_text_append_escaped(out, v->description);
		fmu_text_append_string(out, "</td></tr>\n");
	}
	fmu_text_append_string(out, "</table>\n");
}

// The particles' positions and velocities, six locals per particle in particle order: one
// sentence, not a row each (a cloth has thousands).
static void append_particle_states(fmu_text* out, const fmu_table* t)
{
	int32_t first = -1, last = -1;
	for (int32_t i = 0; i < t->count; ++i) {
		if (is_particle_state(&t->variables[i])) {
			if (first < 0)
				first = i;
			last = i;
		}
	}
	fmu_text_append_string(out, "<h2 id=\"particles\">particles</h2>\n<p>");
	if (first < 0) {
		fmu_text_append_string(out,
		                       "The model file's settings leave the particles' positions and velocities out "
		                       "(<code>\"particle_variables\": false</code>): only the ports and energies "
		                       "above can be read.</p>\n");
		return;
	}
	fmu_text_append_string(out, "Every particle's position [m] and velocity [m/s], locals read at any "
	                            "communication point: <code>");
	fmu_text_append_escaped(out, t->variables[first].name);
	fmu_text_append_string(out, "</code> &hellip; <code>");
	fmu_text_append_escaped(out, t->variables[last].name);
	fmu_text_appendf(
	    out,
	    "</code>, value references %d to %d (<code>p[i].x</code>, <code>.y</code>, <code>.z</code>, "
	    "<code>.vx</code>, <code>.vy</code>, <code>.vz</code> of particle i at value references "
	    "%d + 6 i to %d + 6 i).</p>\n",
	    (int)first, (int)last, (int)first, (int)first + 5);
}

char* fmu_documentation_html(const fmu_table* t, bool licenses)
{
	fmu_text out = {NULL, 0, 0, false};
	char stop[SM_NUMBER_TEXT_CAPACITY], step[SM_NUMBER_TEXT_CAPACITY], tolerance[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(t->stop_time, stop);
	sm_format_number(t->step_size, step);
	sm_format_number(t->tolerance, tolerance);

	fmu_text_append_string(&out,
	                       "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>");
	fmu_text_append_escaped(&out, t->model_name);
	fmu_text_append_string(
	    &out,
	    "</title>\n<style>\nbody { font-family: sans-serif; max-width: 72em; margin: 2em auto; line-height: 1.4; }\n"
	    "table { border-collapse: collapse; }\nth, td { border: 1px solid #bbb; padding: 0.2em 0.5em; "
	    "text-align: left; vertical-align: top; }\n</style>\n</head>\n<body>\n<h1>");
	fmu_text_append_escaped(&out, t->model_name);
	fmu_text_append_string(&out, "</h1>\n<p id=\"description\">");
	fmu_text_append_escaped(&out, t->description);
	fmu_text_appendf(
	    &out,
	    "</p>\n<p>An FMI 2.0 Co-Simulation FMU made by springmass %s from the model file in "
	    "<code>resources/model.json</code> (with the parameter values of <code>resources/parameters.txt</code>, "
	    "when there is one). Model identifier <code>%s</code>, GUID <code>%s</code>.</p>\n",
	    SPRINGMASS_VERSION_STRING, t->model_identifier, t->guid);

	fmu_text_appendf(
	    &out,
	    "<h2 id=\"simulating\">simulating it</h2>\n<ul>\n"
	    "<li>Default experiment: from 0 s to %s s in communication steps of %s s, relative tolerance %s "
	    "(<code>solver.rtol</code>).</li>\n"
	    "<li>Each <code>fmi2DoStep</code> integrates to the communication point with SUNDIALS CVODE, holding the "
	    "inputs at the values set before it, or extrapolating them with the first derivatives "
	    "<code>fmi2SetRealInputDerivatives</code> gives (<code>canInterpolateInputs</code>): a force grows "
	    "linearly, a motion port accelerates with its velocity's derivative. A spring with a "
	    "break strain breaks at the instant its strain crosses it, found by root finding.</li>\n"
	    "<li>Give the stop time to <code>fmi2SetupExperiment</code>: while the inputs are held, CVODE then "
	    "steps on past the communication points and the outputs are interpolated from its steps, which "
	    "takes fewer internal steps. Without a stop time every communication point ends an internal step.</li>\n"
	    "<li>A step the solver cannot complete returns <code>fmi2Discard</code>; "
	    "<code>fmi2GetRealStatus(fmi2LastSuccessfulTime)</code> gives the time reached. A call in the wrong "
	    "state or with a bad argument returns <code>fmi2Error</code> with a logged message and changes "
	    "nothing.</li>\n"
	    "<li>The FMU state can be got, set and serialised; directional derivatives and the first time "
	    "derivatives of the outputs (<code>maxOutputDerivativeOrder</code> 1) are provided. Log "
	    "categories: <code>logEvents</code>, <code>logStatusWarning</code>, <code>logStatusDiscard</code>, "
	    "<code>logStatusError</code>, <code>logSolver</code>.</li>\n</ul>\n",
	    stop, step, tolerance);

	append_table(
	    &out, t, SECTION_INPUTS, "inputs",
	    "Set before each step and held over it, or extrapolated with the first derivatives "
	    "<code>fmi2SetRealInputDerivatives</code> gives: a force port's force, P.fx + d(P.fx)/dt (t - t_n); a "
	    "motion port's position P.x and velocity P.vx, along which its particle moves, at P.x + P.vx s + "
	    "d(P.vx)/dt s^2 / 2 (s = t - t_n), t_n the communication point at which the port's inputs or their "
	    "derivatives were last set (the step's start for a master that sets them every step). A motion port "
	    "starts from its inputs' "
	    "start values, whatever parameters the model file places its particle with.");
	append_table(&out, t, SECTION_OUTPUTS, "outputs", "The model at each communication point.");
	append_table(
	    &out, t, SECTION_PARAMETERS, "parameters",
	    "Fixed ones are set before <code>fmi2ExitInitializationMode</code>; tunable ones also between "
	    "steps (each change restarts the solver).");
	append_table(
	    &out, t, SECTION_CONSTANTS, "constants",
	    "Parameters of the model file that set its structure (a count, which particle a reference names: a "
	    "port's, a spring's end, a load's): fixed when the FMU was made.");
	append_particle_states(&out, t);

	if (licenses)
		fmu_text_append_string(
		    &out,
		    "<h2 id=\"licences\">licences</h2>\n<p>The FMU carries springmass (BSD 2-Clause) and other people's "
		    "software: <a href=\"licenses/license.txt\">licenses/license.txt</a> says which licence covers which "
		    "library. "
		    "Read it before passing the FMU on.</p>\n");
	fmu_text_append_string(&out, "</body>\n</html>\n");

	if (out.failed) {
		free(out.data);
		return NULL;
	}
	return out.data;
}

// springmass run: simulates a model file with CVODE and writes a CSV of its ports and energies,
// optionally every particle's position and a ParaView series (VTK XML polydata + .pvd index).
#define _POSIX_C_SOURCE 200809L

#include "cli_common.h"
#include "cli_inputs.h"
#include "cli_progress.h"
#include "cli_signals.h"
#include "commands.h"

#include "springmass/model_file.h"
#include "springmass/simulation.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void usage(FILE* out)
{
	fprintf(out,
	        "usage: springmass run MODEL [options]\n"
	        "\n"
	        "Simulates the model file MODEL from its initial state and writes one CSV row per output\n"
	        "time: time [s], every port's quantities (force port P: P.x P.y P.z [m] P.vx P.vy P.vz [m/s];\n"
	        "motion port P: P.fx P.fy P.fz [N], the force the model exerts on what drives it; probe P:\n"
	        "P.x .. P.vz), energy.kinetic, energy.elastic, energy.gravity, energy.dissipated and\n"
	        "energy.input (the inputs' work) [J].\n"
	        "Without --input, force ports get no force, and a motion port's particle moves as the file\n"
	        "says (mark it fixed to hold it). An option not given takes the file's \"simulation\"\n"
	        "setting; the defaults below are those of a file that gives none.\n");
	fprintf(out,
	        "\n"
	        "options:\n"
	        "  --t-end T              end time [s]\n"
	        "  --output-interval DT   time between rows [s]; T / DT at most 1e9\n"
	        "  -o, --output FILE      CSV file (default NAME.csv, NAME the model's name; - for stdout)\n"
	        "  --input FILE           the ports' inputs over time (- for stdin): a CSV as fmpy writes,\n"
	        "                         \"time\" and then any of force port P's P.fx P.fy P.fz [N] and motion\n"
	        "                         port P's P.x P.y P.z [m], P.vx P.vy P.vz [m/s]; linear between rows\n"
	        "                         (a repeated time is a jump), held before the first and after the\n"
	        "                         last. A motion port named there is driven: along the positions\n"
	        "                         given (at their slope), or with the velocities given (from the\n"
	        "                         positions, or from where it has got); its other components\n"
	        "                         keep the file's initial position and velocity. An output row\n"
	        "                         at the time of a jump shows the state after it\n"
	        "  --positions            also every particle's position (columns particle.NAME.x,\n"
	        "                         particle.NAME.y, particle.NAME.z [m])\n"
	        "  --vtk DIR              also a ParaView series: DIR/NAME_<k>.vtp per row (XML polydata:\n"
	        "                         particles as points with their velocity [m/s], intact springs\n"
	        "                         as lines with their tension [N], number (spring) and, if all\n"
	        "                         have a rest length, strain [1]) and the index DIR/NAME.pvd\n"
	        "                         (files NAME_<k>.vtp of an earlier, longer run there are removed)\n"
	        "  --solver NAME          linear solver of BDF: auto, dense, klu, pcg, cholmod (Adams\n"
	        "                         uses none)\n"
	        "  --method NAME          bdf (default) or adams\n"
	        "  --rtol R               relative tolerance [1]\n"
	        "  --atol A               absolute tolerance of positions [m] and velocities [m/s],\n"
	        "                         at least 1e-150\n"
	        "  --atol-position A      absolute tolerance of positions alone [m] (wins over --atol)\n"
	        "  --atol-velocity A      absolute tolerance of velocities and of the energies\n"
	        "                         integrated alone [m/s], [J] (wins over --atol)\n"
	        "  --max-steps N          internal steps allowed per output interval, or per stretch\n"
	        "                         between --input rows that change a slope within one\n"
	        "                         (default 100000)\n"
	        "  --max-step H           largest internal step [s]; 0 for no limit\n"
	        "  --threads N            threads for the pcg solver on models of 4000 free particles or\n"
	        "                         more (default: every processor it may run on; at most 4);\n"
	        "                         the results are the same with any count\n"
	        "  --stop-at-outputs      end an internal step at every output time, as an FMU given no\n"
	        "                         stop time does at its communication points (more steps); by\n"
	        "                         default the rows are interpolated from the solver's steps\n"
	        "  --jacobian NAME        exact or definite (the definiteness-preserving variant; the pcg\n"
	        "                         and cholmod solvers use it for their matrix whatever is chosen)\n"
	        "  --input-changes NAME   restart (default): CVODE restarts at an --input jump its\n"
	        "                         history cannot carry; keep: never\n"
	        "  --stability-limit-detection on|off\n"
	        "                         BDF lowers its order where its steps would go unstable on\n"
	        "                         lightly damped vibrations (default on)\n"
	        "  --set PARAM=VALUE      changes a named parameter (repeatable)\n"
	        "  -q, --quiet            no progress line and no summary on stderr (errors only)\n"
	        "  -h, --help             this text\n");
	fprintf(out, "\n"
	             "A progress line goes to stderr for runs longer than a second, and a summary at the end:\n"
	             "the solver's statistics (the pcg and cholmod solvers evaluate the forces with the\n"
	             "Jacobians, in one pass timed as Jacobians), the springs that broke and the energy\n"
	             "balance. Exit status: 0 success, 1 bad model or input signals, T / DT above 1e9,\n"
	             "solver failure or output that cannot be written, 2 usage error. Stopped by a signal\n"
	             "(Ctrl-C, a kill, a closed pipe), it ends after the row it was writing, its outputs whole\n"
	             "up to there, with the signal's status.\n");
}

// Prints that an option's value is refused, why (`what`, naming the option) and the value as
// given, escaped (cli_shown_text).
static void refuse_value(const char* what, const char* value)
{
	cli_shown shown = {0};
	fprintf(stderr, "springmass run: %s, got '%s'\n", what, cli_shown_text(&shown, value));
	cli_shown_free(&shown);
}

// A finite decimal number > 0 (cli_parse_number); prints what is wrong and returns 1 if not.
static int parse_positive(const char* option, const char* text, double* value)
{
	double v;
	if (!cli_parse_number(text, &v)) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass run: %s expects a finite number, got '%s'\n", option,
		        cli_shown_text(&shown, text));
		cli_shown_free(&shown);
		return 1;
	}
	if (!(v > 0.0)) {
		fprintf(stderr, "springmass run: %s must be > 0, got '%s'\n", option, text);
		return 1;
	}
	*value = v;
	return 0;
}

typedef struct run_options {
	const char* model;
	const char* output;
	const char* vtk_dir;
	const char* input;
	double t_end;
	double interval;
	double rtol;
	double atol;
	double atol_position;
	double atol_velocity;
	double max_steps;
	long threads;
	double max_step;
	bool max_step_given;
	const char* jacobian;
	const char* input_changes;
	int stability_limit_detection;  // 1 on, 0 off, -1 the file's setting
	const char* solver;
	const char* method;
	bool positions;
	bool quiet;
	bool stop_at_outputs;
	int set_count;
	const char** sets;
} run_options;

// Column header: ports, energies, positions. A port's columns are PORT.x and so on, with PORT a C
// identifier; a particle's are particle.NAME.x, so that they never take a port's name (a port
// and its particle are often named alike) whatever the particle's name.
static void write_header(FILE* csv, const sm_document* doc, const sm_model* model, bool positions)
{
	fprintf(csv, "time");
	for (int32_t p = 0; p < sm_document_port_count(doc); p++) {
		const sm_port port = sm_document_port(doc, p);
		if (port.kind == SM_PORT_MOTION)
			fprintf(csv, ",%s.fx,%s.fy,%s.fz", port.name, port.name, port.name);
		else
			fprintf(csv, ",%s.x,%s.y,%s.z,%s.vx,%s.vy,%s.vz", port.name, port.name, port.name, port.name,
			        port.name, port.name);
	}
	fprintf(csv, ",energy.kinetic,energy.elastic,energy.gravity,energy.dissipated,energy.input");
	if (positions)
		for (int32_t i = 0; i < sm_model_particle_count(model); i++) {
			// An unnamed particle is p[i], primed as often as needed to be no other particle's name
			// (an explicit particle may be named "p[1]", and a rope "p" names its particles so).
			const char* name = sm_document_particle_name(doc, i);
			char fallback[64];
			if (name == NULL) {
				int length = snprintf(fallback, sizeof fallback, "p[%d]", (int)i);
				while (sm_document_particle_index(doc, fallback) >= 0 && length + 1 < (int)sizeof fallback) {
					fallback[length++] = '\'';
					fallback[length] = '\0';
				}
				name = fallback;
			}
			for (int c = 0; c < 3; c++) {
				fputc(',', csv);
				cli_csv_field(csv, "particle.", name, c == 0 ? ".x" : c == 1 ? ".y" : ".z");
			}
		}
	fprintf(csv, "\n");
}

// The values as CSV fields (cli_csv_number).
static void put_values(FILE* csv, const double* values, size_t count)
{
	for (size_t k = 0; k < count; k++)
		cli_csv_number(csv, values[k]);
}

// Kinetic + elastic + gravitational + dissipated energy - the inputs' work since work_origin [J]:
// constant but for the integration's error (and BDF's damping of oscillations, docs/simulation.md).
static double energy_balance(const sm_simulation* sim, double work_origin)
{
	const sm_energies e = sm_simulation_energies(sim);
	return e.kinetic + e.elastic + e.gravity + sm_simulation_dissipated_energy(sim) -
	       (sm_simulation_input_work(sim) - work_origin);
}

// work_origin: the inputs' work at the start, the time-0 inputs given [J] (it counts from there).
static void write_row(FILE* csv, const sm_document* doc, const sm_simulation* sim, double* forces,
                      double work_origin, bool positions)
{
	const double* x = sm_simulation_positions(sim);
	const double* v = sm_simulation_velocities(sim);
	const int32_t n = sm_model_particle_count(sm_simulation_model(sim));
	char time[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(sm_simulation_time(sim), time);
	fputs(time, csv);
	bool have_forces = false;
	for (int32_t p = 0; p < sm_document_port_count(doc); p++) {
		const sm_port port = sm_document_port(doc, p);
		const size_t i = 3 * (size_t)port.particle;
		if (port.kind == SM_PORT_MOTION) {
			if (!have_forces) {
				sm_simulation_forces(sim, forces);
				have_forces = true;
			}
			put_values(csv, forces + i, 3);
		} else {
			put_values(csv, x + i, 3);
			put_values(csv, v + i, 3);
		}
	}
	const sm_energies e = sm_simulation_energies(sim);
	const double energies[5] = {e.kinetic, e.elastic, e.gravity, sm_simulation_dissipated_energy(sim),
	                            sm_simulation_input_work(sim) - work_origin};
	put_values(csv, energies, 5);
	if (positions)
		put_values(csv, x, 3 * (size_t)n);
	fprintf(csv, "\n");
}

// Writes count values as the text of a DataArray, `per_line` to a line; only the intact springs'
// where `model` is given (one value per spring).
static void write_vtp_values(FILE* f, const double* values, int32_t count, int per_line,
                             const sm_model* model)
{
	for (int32_t i = 0; i < count; i++) {
		if (model != NULL && !sm_model_spring_enabled(model, i))
			continue;
		for (int c = 0; c < per_line; c++)
			fprintf(f, c + 1 < per_line ? "%.9g " : "%.9g\n",
			        values[(size_t)per_line * (size_t)i + (size_t)c]);
	}
}

// One VTK XML polydata file (.vtp, the format of the files a ParaView .pvd index names: its reader
// takes no legacy .vtk file): the particles as points with their velocities, the intact springs as
// lines with their tension [N], when every one has a rest length (a zero-length spring has no
// strain) their strain, and their spring numbers; the time as the field TimeValue. springs holds 2
// values per spring of scratch. False, with errno saying why (0: a write error), when the file
// cannot be written: the caller reports it, after ending its progress line.
static bool write_vtp(const char* path, const sm_simulation* sim, double* springs)
{
	const sm_model* model = sm_simulation_model(sim);
	const double* x = sm_simulation_positions(sim);
	const double* v = sm_simulation_velocities(sim);
	FILE* f = fopen(path, "w");
	if (f == NULL)
		return false;
	const int32_t n = sm_model_particle_count(model);
	const int32_t count = sm_model_spring_count(model);
	double *tension = springs, *strain = springs + count;
	sm_model_spring_states(model, x, v, NULL, strain, tension);
	bool every_strain = true;
	int32_t intact = 0;
	for (int32_t s = 0; s < count; s++)
		if (sm_model_spring_enabled(model, s)) {
			intact++;
			every_strain = every_strain && !isnan(strain[s]);
		}
	char time[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(sm_simulation_time(sim), time);
	fprintf(f,
	        CLI_VTP_HEADER " version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n<FieldData>\n"
	                       "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
	                       "format=\"ascii\">%s</DataArray>\n</FieldData>\n"
	                       "<Piece NumberOfPoints=\"%d\" NumberOfVerts=\"0\" NumberOfLines=\"%d\" "
	                       "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
	        time, (int)n, (int)intact);
	fprintf(f, "<PointData Vectors=\"velocity\">\n<DataArray type=\"Float64\" Name=\"velocity\" "
	           "NumberOfComponents=\"3\" format=\"ascii\">\n");
	write_vtp_values(f, v, n, 3, NULL);
	fprintf(f, "</DataArray>\n</PointData>\n");
	if (intact > 0) {
		fprintf(f, "<CellData Scalars=\"tension\">\n<DataArray type=\"Float64\" Name=\"tension\" "
		           "format=\"ascii\">\n");
		write_vtp_values(f, tension, count, 1, model);
		fprintf(f, "</DataArray>\n");
		if (every_strain) {
			fprintf(f, "<DataArray type=\"Float64\" Name=\"strain\" format=\"ascii\">\n");
			write_vtp_values(f, strain, count, 1, model);
			fprintf(f, "</DataArray>\n");
		}
		// Each line's spring number, as messages give it: once a spring has broken, the lines after
		// its own are no longer at their springs' numbers.
		fprintf(f, "<DataArray type=\"Int32\" Name=\"spring\" format=\"ascii\">\n");
		for (int32_t s = 0; s < count; s++)
			if (sm_model_spring_enabled(model, s))
				fprintf(f, "%d\n", (int)s);
		fprintf(f, "</DataArray>\n</CellData>\n");
	}
	fprintf(f, "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
	cli_vtk_points(f, n, x);
	fprintf(f, "</DataArray>\n</Points>\n");
	if (intact > 0) {
		fprintf(f, "<Lines>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
		for (int32_t s = 0; s < count; s++) {
			if (!sm_model_spring_enabled(model, s))
				continue;
			sm_spring_def d;
			sm_model_get_spring(model, s, &d);
			fprintf(f, "%d %d\n", (int)d.a, (int)d.b);
		}
		fprintf(f, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
		for (int32_t k = 1; k <= intact; k++)
			fprintf(f, "%lld\n", 2LL * k);
		fprintf(f, "</DataArray>\n</Lines>\n");
	}
	fprintf(f, "</Piece>\n</PolyData>\n</VTKFile>\n");
	// As cli_close: a failed write leaves data in the buffer, so fclose fails again and sets errno.
	const bool failed = ferror(f) != 0;
	errno = 0;
	return fclose(f) == 0 && !failed;
}

// A run stopped from outside (Ctrl-C, a kill, the reader of a pipe gone; cli_signals.h) ends after
// the row being written, with every file whole: the CSV's rows up to there, the series' index
// closed.
// The progress line (cli_progress.h), shown after output rows and, through the simulation's on_step
// hook, after internal steps, so that a long output interval does not look like a hang.
typedef struct run_progress {
	cli_progress line;
	double t_end;  // [s]
} run_progress;

static void show_progress(run_progress* p, double t, bool last_row)
{
	if (!cli_progress_due(&p->line, last_row))
		return;
	char line[128];
	snprintf(line, sizeof line, "springmass run: t = %.4g of %.4g s (%3.0f %%), %.1f s", t, p->t_end,
	         100.0 * t / p->t_end, cli_wall_clock() - p->line.start);
	cli_progress_show(&p->line, line);
}

// After every internal step: the progress line (unless quiet) and whether to go on.
static bool on_internal_step(void* context, double t)
{
	if (context != NULL)
		show_progress(context, t, false);
	return cli_stop_signal == 0;
}

// parse_arguments: a usage error after which the usage follows (an unknown option, a missing
// value or model file), rather than a value refused with its own message (2).
#define USAGE_ERROR 3

static int parse_arguments(int argc, char** argv, run_options* o)
{
	for (int i = 1; i < argc; i++) {
		const char* a = argv[i];
		const bool has_value = i + 1 < argc;
		if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
			usage(stdout);
			return -1;
		} else if (strcmp(a, "--positions") == 0) {
			o->positions = true;
		} else if (strcmp(a, "--stop-at-outputs") == 0) {
			o->stop_at_outputs = true;
		} else if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
			o->quiet = true;
		} else if (a[0] == '-' && a[1] != '\0') {
			static const char* const with_value[] = {"--t-end",
			                                         "--output-interval",
			                                         "--rtol",
			                                         "--atol",
			                                         "--atol-position",
			                                         "--atol-velocity",
			                                         "--max-steps",
			                                         "--max-step",
			                                         "--jacobian",
			                                         "--output",
			                                         "-o",
			                                         "--vtk",
			                                         "--solver",
			                                         "--method",
			                                         "--set",
			                                         "--threads",
			                                         "--input",
			                                         "--input-changes",
			                                         "--stability-limit-detection"};
			bool known = false;
			for (size_t k = 0; k < sizeof with_value / sizeof with_value[0]; k++)
				known = known || strcmp(a, with_value[k]) == 0;
			if (!known)
				return cli_model_argument("run", a, &o->model) != 0 ? USAGE_ERROR : 0;
			if (!has_value) {
				fprintf(stderr, "springmass run: %s needs a value\n\n", a);
				return USAGE_ERROR;
			}
			const char* value = argv[++i];
			if (strcmp(a, "--t-end") == 0) {
				if (parse_positive(a, value, &o->t_end))
					return 2;
			} else if (strcmp(a, "--output-interval") == 0) {
				if (parse_positive(a, value, &o->interval))
					return 2;
			} else if (strcmp(a, "--rtol") == 0) {
				if (parse_positive(a, value, &o->rtol))
					return 2;
				if (!(o->rtol < 1.0)) {
					fprintf(stderr, "springmass run: --rtol must be < 1, got '%s'\n", value);
					return 2;
				}
				if (!(o->rtol >= SM_MIN_RELATIVE_TOLERANCE)) {
					char floor[SM_NUMBER_TEXT_CAPACITY];
					sm_format_number(SM_MIN_RELATIVE_TOLERANCE, floor);
					fprintf(
					    stderr,
					    "springmass run: --rtol must be at least %s, the machine epsilon (CVODE cannot meet a "
					    "smaller relative tolerance), got '%s'\n",
					    floor, value);
					return 2;
				}
			} else if (strcmp(a, "--threads") == 0) {
				if (!cli_parse_count(value, 1, 1024, &o->threads)) {
					refuse_value("--threads needs a count from 1 to 1024", value);
					return 2;
				}
			} else if (strcmp(a, "--max-steps") == 0) {
				long steps;
				if (!cli_parse_count(value, 1, 2e9, &steps)) {
					refuse_value("--max-steps needs a count from 1 to 2e9", value);
					return 2;
				}
				o->max_steps = (double)steps;
			} else if (strncmp(a, "--atol", 6) == 0) {
				double* atol = strcmp(a, "--atol") == 0            ? &o->atol
				               : strcmp(a, "--atol-position") == 0 ? &o->atol_position
				                                                   : &o->atol_velocity;
				if (parse_positive(a, value, atol))
					return 2;
				if (!(*atol >= SM_MIN_ABSOLUTE_TOLERANCE)) {
					fprintf(
					    stderr,
					    "springmass run: %s must be at least %g (CVODE's error norm overflows below), got '%s'\n",
					    a, SM_MIN_ABSOLUTE_TOLERANCE, value);
					return 2;
				}
			} else if (strcmp(a, "--max-step") == 0) {
				if (!cli_parse_number(value, &o->max_step) || !(o->max_step >= 0.0)) {
					refuse_value("--max-step needs a step >= 0 [s] (0: no limit)", value);
					return 2;
				}
				if (o->max_step > 0.0 && o->max_step <= SM_MAX_STEP_FLOOR) {
					char least[SM_NUMBER_TEXT_CAPACITY];
					sm_format_number(SM_MAX_STEP_FLOOR, least);
					fprintf(
					    stderr,
					    "springmass run: --max-step needs 0 (no limit) or a step above %s s (1 / DBL_MAX: "
					    "CVODE takes its inverse), got '%s'\n",
					    least, value);
					return 2;
				}
				o->max_step_given = true;
			} else if (strcmp(a, "--jacobian") == 0) {
				o->jacobian = value;
			} else if (strcmp(a, "--input-changes") == 0) {
				o->input_changes = value;
			} else if (strcmp(a, "--stability-limit-detection") == 0) {
				if (strcmp(value, "on") != 0 && strcmp(value, "off") != 0) {
					refuse_value("--stability-limit-detection takes on or off", value);
					return 2;
				}
				o->stability_limit_detection = strcmp(value, "on") == 0;
			} else if (strcmp(a, "--output") == 0 || strcmp(a, "-o") == 0) {
				o->output = value;
			} else if (strcmp(a, "--vtk") == 0) {
				o->vtk_dir = value;
			} else if (strcmp(a, "--input") == 0) {
				o->input = value;
			} else if (strcmp(a, "--solver") == 0) {
				o->solver = value;
			} else if (strcmp(a, "--method") == 0) {
				o->method = value;
			} else {  // --set, the last of with_value
				o->sets[o->set_count++] = value;
			}
		} else if (cli_model_argument("run", a, &o->model) != 0) {
			return USAGE_ERROR;
		}
	}
	if (cli_model_given("run", o->model) != 0)
		return USAGE_ERROR;
	if (o->input != NULL &&
	    cli_check_output("run", "-o", o->output, o->input, "the input signals", true) != 0)
		return 2;
	return cli_check_output("run", "-o", o->output, o->model, "the model file", true);
}

// Whether a file of the ParaView series (the index or a frame) would overwrite the model file,
// the input signals or the CSV (NULL: standard output); prints which and returns 2 if so.
static int series_file_clashes(const char* path, const run_options* o, const char* csv_path)
{
	const char *what = "the model file", *file = o->model, *instead = "folder";
	if (!cli_same_file(path, o->model)) {
		what = "the input signals", file = o->input;
		if (o->input == NULL || !cli_same_file(path, o->input)) {
			what = "the CSV output", file = csv_path, instead = "folder or -o";
			if (csv_path == NULL || !cli_same_file(path, csv_path))
				return 0;
		}
	}
	cli_shown shown = {0};
	fprintf(stderr, "springmass run: --vtk %s: the series' file %s would overwrite %s %s; give another %s\n",
	        cli_shown_path(&shown, o->vtk_dir), cli_shown_path(&shown, path), what,
	        cli_shown_path(&shown, file), instead);
	cli_shown_free(&shown);
	return 2;
}

int sm_cmd_run(int argc, char** argv)
{
	run_options o;
	memset(&o, 0, sizeof o);
	o.stability_limit_detection = -1;
	o.sets = calloc((size_t)argc + 1, sizeof(char*));
	if (!o.sets)
		return 1;
	int st = parse_arguments(argc, argv, &o);
	if (st != 0) {
		free(o.sets);
		if (st == USAGE_ERROR)
			usage(stderr);
		return st < 0 ? 0 : 2;
	}

	int status = 1;
	sm_document* doc = NULL;
	sm_model* model = NULL;
	sm_simulation* sim = NULL;
	cli_inputs* inputs = NULL;
	FILE* csv = NULL;
	FILE* pvd = NULL;
	double* forces = NULL;
	double* spring_values = NULL;
	char* path = NULL;
	char* csv_default = NULL;  // <model>.csv when no --output is given
	char* pvd_path = NULL;
	const char* csv_name = NULL;  // for messages
	sm_error err = {SM_OK, ""};

	if ((status = cli_load_model("run", o.model, o.sets, o.set_count, &doc, &model)) != 0)
		goto done;
	status = 1;
	sm_document_settings settings = sm_document_get_settings(doc);
	const double t_end = o.t_end > 0.0 ? o.t_end : settings.stop_time;
	const double interval = o.interval > 0.0 ? o.interval : settings.output_interval;
	const long rows = cli_output_rows(t_end, interval);
	if (rows < 0) {
		char end[SM_NUMBER_TEXT_CAPACITY], step[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(t_end, end);
		sm_format_number(interval, step);
		// Either number may come from the model file: the message says which did.
		fprintf(stderr,
		        "springmass run: %s s (%s) / %s s (%s) would make more than %g output rows: give a larger "
		        "interval\n",
		        end, o.t_end > 0.0 ? "--t-end" : "the model's simulation.stop_time", step,
		        o.interval > 0.0 ? "--output-interval" : "the model's simulation.output_interval",
		        CLI_MAX_ROWS);
		goto done;
	}
	sm_simulation_def def = settings.solver;
	if (o.rtol > 0.0)
		def.relative_tolerance = o.rtol;
	if (o.atol > 0.0)
		def.absolute_tolerance_position = def.absolute_tolerance_velocity = o.atol;
	if (o.atol_position > 0.0)
		def.absolute_tolerance_position = o.atol_position;
	if (o.atol_velocity > 0.0)
		def.absolute_tolerance_velocity = o.atol_velocity;
	if (o.max_steps > 0.0)
		def.max_steps = (int32_t)o.max_steps;
	if (o.max_step_given)
		def.max_step = o.max_step;
	if (o.stability_limit_detection >= 0)
		def.stability_limit_detection = o.stability_limit_detection == 1;
	// The tool owns its process: every processor, unless told otherwise.
	const long online = sysconf(_SC_NPROCESSORS_ONLN);
	def.threads = (int32_t)(o.threads > 0 ? o.threads : online > 0 ? (online < 1024 ? online : 1024) : 1);
	if (o.solver) {
		if (sm_linear_solver_from_name(o.solver, &def.solver) != SM_OK) {
			cli_shown shown = {0};
			fprintf(stderr,
			        "springmass run: --solver: unknown linear solver '%s' (auto, dense, klu, pcg, cholmod)\n",
			        cli_shown_text(&shown, o.solver));
			cli_shown_free(&shown);
			status = 2;
			goto done;
		}
	}
	if (o.method && sm_method_from_name(o.method, &def.method) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass run: --method: unknown method '%s' (bdf, adams)\n",
		        cli_shown_text(&shown, o.method));
		cli_shown_free(&shown);
		status = 2;
		goto done;
	}
	if (o.jacobian && sm_jacobian_variant_from_name(o.jacobian, &def.jacobian) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass run: --jacobian: unknown Jacobian '%s' (exact, definite)\n",
		        cli_shown_text(&shown, o.jacobian));
		cli_shown_free(&shown);
		status = 2;
		goto done;
	}
	if (o.input_changes &&
	    sm_input_changes_from_name(o.input_changes, &def.restart_on_input_change) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass run: unknown --input-changes '%s' (restart, keep)\n",
		        cli_shown_text(&shown, o.input_changes));
		cli_shown_free(&shown);
		status = 2;
		goto done;
	}
	if (o.input != NULL) {
		inputs = cli_inputs_read(o.input, doc);
		if (inputs == NULL || cli_inputs_drive(inputs, model) != SM_OK)
			goto done;
	}
	if (!o.quiet) {
		cli_warn_coarse_tolerances(stderr, "springmass run: warning: ", model, &def);
		cli_warn_tight_tolerances(stderr, "springmass run: warning: ", doc, model, &def);
	}
	run_progress prog = {.t_end = t_end};
	def.on_step = on_internal_step;
	def.on_step_context = o.quiet ? NULL : &prog;
	sim = sm_simulation_create(model, &def, &err);
	if (!sim) {
		fputs("springmass run: ", stderr);
		cli_write_named(stderr, doc, model, err.message);
		fputc('\n', stderr);
		goto done;
	}
	char input_problem[SM_ERROR_MESSAGE_CAPACITY + 128] = "";
	if (inputs != NULL && cli_inputs_apply(inputs, sim, input_problem, sizeof input_problem) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass run: --input %s: %s\n", cli_shown_path(&shown, o.input), input_problem);
		cli_shown_free(&shown);
		goto done;
	}
	const double work_origin = sm_simulation_input_work(sim);
	const double balance_at_start = energy_balance(sim, work_origin);
	const char* name = sm_document_name(doc);
	const size_t path_capacity = strlen(name) + (o.vtk_dir ? strlen(o.vtk_dir) : 0) + 64;
	path = malloc(path_capacity);
	pvd_path = malloc(path_capacity);
	csv_default = malloc(strlen(name) + 5);
	forces = malloc(sizeof(double) * (3 * (size_t)sm_model_particle_count(model) + 1));
	spring_values = malloc(sizeof(double) * (2 * (size_t)sm_model_spring_count(model) + 1));
	if (!path || !pvd_path || !csv_default || !forces || !spring_values)
		goto done;
	sprintf(csv_default, "%s.csv", name);
	const bool csv_to_stdout = o.output && strcmp(o.output, "-") == 0;
	csv_name = csv_to_stdout ? "standard output" : o.output ? o.output : csv_default;
	const char* csv_file = csv_to_stdout ? NULL : csv_name;  // the CSV's file, if it has one
	// No file the run writes may be the model file (-o is checked with the arguments) or an OBJ
	// file its meshes read, nor the CSV one of the series' files (each frame is checked before it
	// is written).
	if (!o.output && o.input && cli_same_file(csv_default, o.input)) {
		cli_shown shown = {0};
		fprintf(stderr,
		        "springmass run: the output %s (NAME.csv, without -o) would overwrite the input signals %s, "
		        "which it reads; give another name with -o\n",
		        csv_default, cli_shown_path(&shown, o.input));
		cli_shown_free(&shown);
		status = 2;
		goto done;
	}
	if (!o.output && cli_same_file(csv_default, o.model)) {
		cli_shown shown = {0};
		fprintf(
		    stderr,
		    "springmass run: the output %s (NAME.csv, without -o) would overwrite the model file %s, which "
		    "it reads; give another name with -o\n",
		    csv_default, cli_shown_path(&shown, o.model));
		cli_shown_free(&shown);
		status = 2;
		goto done;
	}
	const int overwrites = cli_check_output_not_mesh_file(
	    "run", o.output ? "-o" : "the output (NAME.csv, without -o)", csv_file, doc);
	if (overwrites != 0) {
		status = overwrites;
		goto done;
	}
	if (cli_check_folder_option("run", "--vtk", o.vtk_dir) != 0 ||
	    cli_check_outputs_apart("run", o.output ? "-o" : "the output (NAME.csv, without -o)", csv_file,
	                            "--vtk", o.vtk_dir) != 0) {
		status = 2;
		goto done;
	}
	// Where the CSV and the series go is checked before either is opened, so that a run refused
	// for one leaves the other as it was (opening the index emptied an earlier one); the CSV may
	// go in the series' folder, made first.
	if (cli_check_output_place("run", "--vtk", o.vtk_dir, true) != 0)
		goto done;
	if (o.vtk_dir) {
		if (cli_make_directory("run", o.vtk_dir) != 0)
			goto done;
		snprintf(pvd_path, path_capacity, "%s/%s.pvd", o.vtk_dir, name);
		if (series_file_clashes(pvd_path, &o, csv_file) != 0) {
			status = 2;
			goto done;
		}
	}
	if (cli_check_output_place("run", o.output ? "-o" : "the output (NAME.csv, without -o)", csv_file,
	                           false) != 0)
		goto done;
	if (o.vtk_dir) {
		pvd = fopen(pvd_path, "w");
		if (!pvd) {
			cli_cannot_write("run", pvd_path);
			goto done;
		}
		fprintf(pvd,
		        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n");
		// The index is written through at every row: one that cannot be is reported at its row, and
		// a run that fails or is stopped leaves on disk an index of every frame written before.
		if (fflush(pvd) != 0) {
			cli_cannot_write("run", pvd_path);
			goto done;
		}
	}
	if (csv_to_stdout) {
		csv = stdout;
	} else {
		csv = fopen(csv_name, "w");
		if (!csv) {
			cli_cannot_write("run", csv_name);
			goto done;
		}
	}
	write_header(csv, doc, model, o.positions);

	cli_progress_start(&prog.line);
	const double start = prog.line.start;
	cli_catch_stop_signals(true);
	// The time of the last row written, as its row gives it, for the messages of a run that ends
	// early: the reader finds that row by it.
	char last_row_text[SM_NUMBER_TEXT_CAPACITY] = "0";
	for (long k = 0; k <= rows; k++) {
		const double t = k == rows ? t_end : (double)k * interval;
		// Between changes of the inputs' course CVODE may step as in one advance up to the next
		// change (t_end without inputs), the rows interpolated from its steps; at a change the
		// run stops and takes the inputs' new course.
		if (cli_stop_signal != 0)
			break;
		if (k > 0 && cli_inputs_advance(inputs, sim, t, o.stop_at_outputs ? t : t_end, input_problem,
		                                sizeof input_problem) != SM_OK) {
			if (cli_stop_signal != 0)  // stopped between internal steps (on_internal_step)
				break;
			cli_progress_end(&prog.line);
			if (input_problem[0] != '\0') {
				cli_shown shown = {0};
				fprintf(stderr, "springmass run: --input %s: %s\n", cli_shown_path(&shown, o.input),
				        input_problem);
				cli_shown_free(&shown);
			} else {
				fputs("springmass run: ", stderr);
				cli_write_named(stderr, doc, model, sm_simulation_last_error(sim));
				fputc('\n', stderr);
			}
			// The library's message is written for a caller that may go on (after its step limit,
			// from the state reached); the run ends here, with the rows written so far.
			fprintf(stderr, "springmass run: stopped; the outputs hold the rows up to t = %s s\n",
			        last_row_text);
			goto done;
		}
		write_row(csv, doc, sim, forces, work_origin, o.positions);
		sm_format_number(t, last_row_text);
		// A full disk or a closed pipe stops the run at once, not after the last step.
		if (ferror(csv) && errno == EPIPE && !cli_signal_ignored(SIGPIPE))
			cli_stop_signal = SIGPIPE;  // the reader has gone: nothing to report to it
		if (ferror(csv) && cli_stop_signal == 0) {
			cli_progress_end(&prog.line);
			cli_cannot_write("run", csv_name);
			goto done;
		}
		if (o.vtk_dir) {
			snprintf(path, path_capacity, "%s/%s_%06ld.vtp", o.vtk_dir, name, k);
			if (series_file_clashes(path, &o, csv_file) != 0) {
				cli_progress_end(&prog.line);
				status = 2;
				goto done;
			}
			if (!write_vtp(path, sim, spring_values)) {
				const int error = errno;
				cli_progress_end(&prog.line);
				errno = error;
				cli_cannot_write("run", path);
				goto done;
			}
			char timestep[SM_NUMBER_TEXT_CAPACITY];
			sm_format_number(t, timestep);
			fprintf(pvd, "<DataSet timestep=\"%s\" file=\"%s_%06ld.vtp\"/>\n", timestep, name, k);
			if (fflush(pvd) != 0) {
				const int error = errno;
				cli_progress_end(&prog.line);
				errno = error;
				cli_cannot_write("run", pvd_path);
				goto done;
			}
		}
		if (!o.quiet)
			show_progress(&prog, t, k == rows);
	}
	cli_progress_end(&prog.line);
	if (cli_stop_signal != 0) {
		if (cli_stop_signal != SIGPIPE)
			fprintf(stderr, "springmass run: stopped by %s; the outputs hold the rows up to t = %s s\n",
			        strsignal(cli_stop_signal), last_row_text);
		goto done;
	}
	if (fflush(csv) != 0 || ferror(csv)) {
		cli_cannot_write("run", csv_name);
		goto done;
	}
	// Files of an earlier run with more rows, which the index does not name.
	if (o.vtk_dir) {
		snprintf(path, path_capacity, "%s/%s_", o.vtk_dir, name);
		const long removed = cli_remove_series_tail(path, 6, rows + 1, ".vtp", CLI_VTP_HEADER);
		if (removed == 1 && !o.quiet)
			fprintf(stderr, "springmass run: removed %s_%06ld.vtp of an earlier run\n", name, rows + 1);
		else if (removed > 1 && !o.quiet)
			fprintf(stderr, "springmass run: removed %s_%06ld.vtp to %s_%06ld.vtp of an earlier run\n", name,
			        rows + 1, name, rows + removed);
	}
	if (!o.quiet) {
		const sm_statistics s = sm_simulation_statistics(sim);
		char end[SM_NUMBER_TEXT_CAPACITY];  // as the last row gives it
		sm_format_number(t_end, end);
		fprintf(
		    stderr,
		    "springmass run: %s to t = %s s with %s%s: %lld steps, %lld right-hand sides, %lld "
		    "Jacobians, %lld linear iterations, %lld error-test and %lld convergence failures, %lld "
		    "restarts, %d spring%s broke; wall %.3f s (forces %.3f, Jacobians %.3f, linear solves %.3f)\n",
		    name, end,
		    def.method == SM_METHOD_ADAMS ? "Adams (fixed point, no linear solver)" : "BDF, solver ",
		    def.method == SM_METHOD_ADAMS ? "" : sm_linear_solver_name(sm_simulation_solver(sim)),
		    (long long)s.steps, (long long)s.rhs_evaluations, (long long)s.jacobian_evaluations,
		    (long long)s.linear_iterations, (long long)s.error_test_failures,
		    (long long)s.convergence_failures, (long long)s.restarts, (int)sm_simulation_break_count(sim),
		    sm_simulation_break_count(sim) == 1 ? "" : "s", cli_wall_clock() - start, s.force_seconds,
		    s.jacobian_seconds, s.linear_solve_seconds);
		for (int32_t b = 0; b < sm_simulation_break_count(sim); b++) {
			const sm_break_event e = sm_simulation_break(sim, b);
			// The time as the library has it, to the digit that reads it back: breaks close together
			// (springs that cross their limits some 1e-10 s apart) are told apart, as in an FMU's log.
			char time[SM_NUMBER_TEXT_CAPACITY], line[96];
			sm_format_number(e.time, time);
			snprintf(line, sizeof line, "  spring %d broke at t = %s s\n", (int)e.spring, time);
			cli_write_named(stderr, doc, model, line);
		}
		const double balance_at_end = energy_balance(sim, work_origin);
		// The loads' potential is counted with gravity's (energy.gravity): said so where there are some.
		double loads[3];
		const char* with_loads = cli_total_load(model, loads) > 0 ? " (with the loads')" : "";
		// Energies beyond a double (a kinetic energy of 1e300 kg at 1e5 m/s) leave no balance to
		// check: their difference, inf - inf, would print as nan.
		char drift[64] = ": beyond a double, no energy balance to check";
		if (isfinite(balance_at_start) && isfinite(balance_at_end))
			snprintf(drift, sizeof drift, " (%+.3g J)", balance_at_end - balance_at_start);
		fprintf(
		    stderr,
		    "springmass run: kinetic + elastic + gravitational%s + dissipated energy - input work: %.9g J "
		    "at the start, %.9g J at the end%s\n",
		    with_loads, balance_at_start, balance_at_end, drift);
	}
	status = 0;

done:
	if (csv && csv != stdout && fclose(csv) != 0 && status == 0) {
		cli_cannot_write("run", csv_name);
		status = 1;
	}
	// The index is closed after a failed run too: ParaView then shows the rows up to the failure.
	if (pvd)
		fprintf(pvd, "</Collection>\n</VTKFile>\n");
	if (pvd && fclose(pvd) != 0 && status == 0) {
		cli_cannot_write("run", pvd_path);
		status = 1;
	}
	free(path);
	free(pvd_path);
	free(csv_default);
	free(forces);
	free(spring_values);
	free(o.sets);
	sm_simulation_destroy(sim);
	cli_inputs_destroy(inputs);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	// Stopped by a signal: the files are whole; the exit status is the signal's, as without a handler.
	cli_end_by_stop_signal();
	return status;
}

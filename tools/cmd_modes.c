// springmass modes: natural frequencies, damping ratios and mode shapes of a model file.
#include "cli_common.h"
#include "cli_progress.h"
#include "commands.h"

#include "springmass/analysis.h"
#include "springmass/model_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static void usage(FILE* out)
{
	fprintf(out,
	        "usage: springmass modes MODEL [options]\n"
	        "\n"
	        "Linearises the model about its initial configuration (or its static equilibrium) with\n"
	        "its fixed particles held (a motion port's particle is free here), and solves\n"
	        "K phi = omega^2 M phi: natural frequencies,\n"
	        "modal damping ratios (from the damping matrix; exact when the damping is proportional,\n"
	        "which is reported) and mass-normalised mode shapes. Zero modes (rigid-body motions, and\n"
	        "mechanisms such as the sideways motion of a straight unstressed chain) have frequency 0.\n"
	        "Also prints the largest communication step suggested for co-simulation (a fraction of\n"
	        "the period of the highest mode listed) and the stability limit of explicit (symplectic\n"
	        "Euler) integration: with every mode listed (-n 0, dense) the smallest of the modes' own\n"
	        "limits, each omega with its modal damping rate; otherwise from omega_max and a bound on the\n"
	        "damping rates. Small models (or -n 0) are solved densely, all modes; large ones by\n"
	        "shift-invert Lanczos on the sparse matrices, the lowest N modes only (then the zero and\n"
	        "unstable counts are among those, and omega_max is an upper bound). Modes of a repeated\n"
	        "frequency are those that diagonalise their damping (docs/analysis.md).\n"
	        "\n"
	        "options:\n"
	        "  -n, --count N          modes listed and written, lowest first (default 10; 0 = all; all or\n"
	        "                         more than the sparse solver gives need --solver dense above %d\n"
	        "                         degrees of freedom, where the dense solver takes minutes)\n"
	        "  --at-equilibrium       linearise about the static equilibrium (springmass statics,\n"
	        "                         with its progress line on stderr once it takes over a second)\n"
	        "  --zero-tolerance R     omega^2 within R of the largest |omega^2| (sparse solver: of its\n"
	        "                         Gershgorin bound) is a zero mode (default 1e-12; lower it for a\n"
	        "                         model whose stiffnesses span more than 1e12)\n"
	        "  --steps-per-period K   communication steps per period of the highest mode listed\n"
	        "                         (default 10)\n"
	        "  -o, --output FILE      write the listed mode shapes as CSV: particle, name, then x, y, z\n"
	        "                         of every mode [1/sqrt(kg), mass-normalised]\n"
	        "  --vtk DIR              write DIR/mode_<k>.vtk per listed mode (ParaView: the shape as\n"
	        "                         the vector field 'shape'; animate with Warp By Vector), and\n"
	        "                         remove the further mode files an earlier run left there\n"
	        "  --solver NAME          auto (default: dense up to %d degrees of freedom or with -n 0),\n"
	        "                         dense (GSL, all modes) or sparse (CHOLMOD + Lanczos, lowest N)\n"
	        "  --set NAME=VALUE       change a parameter of the model file first (repeatable)\n"
	        "  -h, --help             this text\n"
	        "\n"
	        "Exit status: 0 success, 1 for a bad model, a failed solve or an output that cannot be\n"
	        "written, 2 for a usage error (also all modes of a model too large for the dense\n"
	        "eigensolver without --solver dense, or more than --solver sparse gives).\n",
	        CLI_DENSE_LIMIT, SM_MODES_DENSE_LIMIT);
}

// Legacy VTK polydata of one mode: particles at the linearisation point, springs as lines, the
// mode shape as a vector field. The title gives the mode's frequency [Hz], or for an unstable mode
// (omega^2 < 0 [1/s^2], no frequency) its omega^2, as the table does.
static int write_mode_vtk(cli_outputs* outputs, const char* path, const sm_model* model, const double* x,
                          const double* shape, int index, double frequency, double omega_squared)
{
	char title[128];
	if (omega_squared < 0.0)
		snprintf(title, sizeof title, "springmass mode %d, unstable: omega^2 = %.9g 1/s^2", index,
		         omega_squared);
	else
		snprintf(title, sizeof title, "springmass mode %d, %.9g Hz", index, frequency);
	FILE* f = cli_vtk_open(outputs, "modes", path, title, model, x);
	if (f == NULL)
		return -1;
	cli_vtk_vectors(f, "shape", sm_model_particle_count(model), shape, true);
	return cli_close("modes", path, f);
}

// The VTK file of mode m (from 0): DIR/mode_<m + 1>.vtk; false, with a message, if it is too long.
static bool mode_path(char* path, size_t size, const char* vtk_dir, int32_t m)
{
	if ((size_t)snprintf(path, size, "%s/mode_%d.vtk", vtk_dir, (int)m + 1) < size)
		return true;
	cli_shown shown = {0};
	fprintf(stderr, "springmass modes: path too long: %s\n", cli_shown_path(&shown, vtk_dir));
	cli_shown_free(&shown);
	return false;
}

static int write_csv(cli_outputs* outputs, const char* path, const sm_document* doc, const sm_modes* modes)
{
	FILE* f = cli_outputs_open(outputs, path);
	if (f == NULL)
		return -1;
	fprintf(f, "particle,name");
	for (int32_t m = 0; m < modes->count; m++)
		fprintf(f, ",mode%d_x,mode%d_y,mode%d_z", (int)m + 1, (int)m + 1, (int)m + 1);
	fprintf(f, "\n");
	const size_t n3 = 3 * (size_t)modes->particle_count;
	for (int32_t i = 0; i < modes->particle_count; i++) {
		const char* name = sm_document_particle_name(doc, i);
		fprintf(f, "%d,", (int)i);
		cli_csv_field(f, "", name != NULL ? name : "", "");
		for (int32_t m = 0; m < modes->count; m++)
			for (int c = 0; c < 3; c++)
				cli_csv_number(f, modes->shapes[(size_t)m * n3 + 3 * (size_t)i + c]);
		fprintf(f, "\n");
	}
	return cli_close("modes", path, f);
}

// The summary and the table of frequencies, periods, omega^2 and damping ratios.
static void print_modes(const sm_modes* modes, bool at_equilibrium, double steps_per_period,
                        double zero_tolerance)
{
	const bool sparse = modes->solver == SM_MODES_SPARSE;
	if (sparse)
		printf(
		    "eigensolver       shift-invert Lanczos (CHOLMOD), the lowest %d modes; largest residual %.2e\n",
		    (int)modes->count, modes->residual);
	else
		printf("eigensolver       dense (GSL), all %d modes; largest residual %.2e\n", (int)modes->dof,
		       modes->residual);
	// A zero mode is one the eigensolver cannot tell from 0 beside the stiffest: a rigid-body motion,
	// a mechanism, or a mode too soft for the model's range of stiffnesses.
	// The sparse path knows only its kept modes: its zero level is relative to the Gershgorin bound
	// on the largest |omega^2| (omega_max^2), not to the largest itself.
	printf("zero modes        %d%s (|omega^2| <= %g of %s: rigid-body motions, mechanisms or modes too "
	       "soft to resolve, see --zero-tolerance%s)\n",
	       (int)modes->zero_count, sparse ? " among the modes listed" : "", zero_tolerance,
	       sparse ? "the Gershgorin bound on the largest, omega_max^2" : "the largest",
	       modes->zero_count > 0 && !at_equilibrium
	           ? "; where the rest shape is stretched, --at-equilibrium gives mechanisms their stiffness"
			   : "");
	if (modes->unstable_count > 0)
		printf("unstable modes    %d%s (omega^2 < 0: the configuration is not a stable rest shape%s)\n",
		       (int)modes->unstable_count, sparse ? " among the modes listed" : "",
		       at_equilibrium ? "" : "; try --at-equilibrium");
	printf("damping           %s (largest normalised coupling %.3g among the modes listed)\n",
	       modes->proportional ? "proportional: the modal damping ratios are exact"
	                           : "not proportional: the damping ratios are the diagonal approximation",
	       modes->damping_coupling);
	printf("\n%6s %16s %16s %16s %14s\n", "mode", "frequency [Hz]", "period [s]", "omega^2 [1/s^2]",
	       "damping ratio");
	double highest = 0.0;
	for (int32_t m = 0; m < modes->count; m++) {
		const double fr = modes->frequency[m];
		highest = fmax(highest, fr);
		char period[32];
		if (fr > 0.0)
			snprintf(period, sizeof period, "%.9g", 1.0 / fr);
		else
			snprintf(period, sizeof period, "%s", modes->omega_squared[m] < 0.0 ? "unstable" : "inf");
		char ratio[32];
		if (isnan(modes->damping_ratio[m]))
			snprintf(ratio, sizeof ratio, "-");
		else
			snprintf(ratio, sizeof ratio, "%.6g", modes->damping_ratio[m]);
		printf("%6d %16.9g %16s %16.9g %14s\n", (int)m + 1, fr, period, modes->omega_squared[m], ratio);
	}
	if (modes->group_cut)
		printf(
		    "%6s mode %d's frequency repeats in mode %d and perhaps beyond: the list ends inside a group of\n"
		    "%6s repeated frequencies, whose listed modes are one arbitrary part of it (list more with -n)\n",
		    "", (int)modes->count, (int)modes->count + 1, "");
	printf("\nhighest frequency        %s%.9g Hz (omega_max = %.9g rad/s, %s %d modes)\n",
	       sparse ? "<= " : "", modes->omega_max / (2.0 * 3.14159265358979323846), modes->omega_max,
	       sparse ? "Gershgorin bound over all" : "of all", (int)modes->dof);
	// With every mode listed the library takes each mode's own damping rate, otherwise the bound on
	// all of them: the line names the one the step comes from. omega_max = 0 with unstable modes is
	// a configuration whose stiffness only pushes, not one without stiffness.
	const bool every_mode = modes->count == modes->dof;
	const char* no_frequency = modes->unstable_count > 0 ? "no mode of positive omega^2" : "no stiffness";
	if (isfinite(modes->explicit_step) && modes->omega_max > 0.0 && every_mode)
		printf("explicit stability limit %.6g s (symplectic Euler, each mode with its own damping rate; "
		       "2/omega_max = %.6g s undamped)\n",
		       modes->explicit_step, 2.0 / modes->omega_max);
	else if (isfinite(modes->explicit_step) && modes->omega_max > 0.0)
		printf(
		    "explicit stability limit %.6g s (symplectic Euler with omega_max and damping rate <= %.6g 1/s; "
		    "2/omega_max = %.6g s undamped)\n",
		    modes->explicit_step, modes->damping_rate_max, 2.0 / modes->omega_max);
	else if (isfinite(modes->explicit_step) && every_mode)
		printf(
		    "explicit stability limit %.6g s (symplectic Euler, each mode with its own damping rate, %s)\n",
		    modes->explicit_step, no_frequency);
	else if (isfinite(modes->explicit_step))
		printf("explicit stability limit %.6g s (symplectic Euler with damping rate <= %.6g 1/s, %s)\n",
		       modes->explicit_step, modes->damping_rate_max, no_frequency);
	if (highest > 0.0)
		printf(
		    "communication step       <= %.6g s (1/%g of the period of the highest mode listed, %.6g Hz)\n",
		    1.0 / (highest * steps_per_period), steps_per_period, highest);
	else
		printf(
		    "communication step       none suggested: no mode listed has a frequency (list more with -n)\n");
}

int sm_cmd_modes(int argc, char** argv)
{
	const char* model_path = NULL;
	const char* csv_path = NULL;
	const char* vtk_dir = NULL;
	const char** settings = calloc((size_t)argc + 1, sizeof *settings);
	int setting_count = 0;
	int at_equilibrium = 0;
	long count = 10;
	sm_modes_solver solver = SM_MODES_AUTO;
	double steps_per_period = 10.0;
	double zero_tolerance = sm_default_modes_def().zero_tolerance;
	if (settings == NULL)
		return 1;
	for (int i = 1; i < argc; i++) {
		const char* a = argv[i];
		const int has_value = i + 1 < argc;
		if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
			usage(stdout);
			free(settings);
			return 0;
		} else if ((strcmp(a, "-n") == 0 || strcmp(a, "--count") == 0) && has_value) {
			if (!cli_parse_count(argv[++i], 0, 100000000, &count)) {
				cli_shown shown = {0};
				fprintf(stderr, "springmass modes: %s needs a count from 0 to 1e8, got '%s'\n", a,
				        cli_shown_text(&shown, argv[i]));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if (strcmp(a, "--at-equilibrium") == 0) {
			at_equilibrium = 1;
		} else if (strcmp(a, "--zero-tolerance") == 0 && has_value) {
			if (!cli_parse_number(argv[++i], &zero_tolerance) ||
			    !(zero_tolerance >= 0.0 && zero_tolerance < 1.0)) {
				cli_shown shown = {0};
				fprintf(stderr, "springmass modes: --zero-tolerance needs a number in [0, 1), got '%s'\n",
				        cli_shown_text(&shown, argv[i]));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if (strcmp(a, "--steps-per-period") == 0 && has_value) {
			if (!cli_parse_number(argv[++i], &steps_per_period) || !(steps_per_period >= 1.0)) {
				cli_shown shown = {0};
				fprintf(stderr, "springmass modes: --steps-per-period needs a finite number >= 1, got '%s'\n",
				        cli_shown_text(&shown, argv[i]));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if ((strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) && has_value) {
			csv_path = argv[++i];
		} else if (strcmp(a, "--vtk") == 0 && has_value) {
			vtk_dir = argv[++i];
		} else if (strcmp(a, "--solver") == 0 && has_value) {
			const char* name = argv[++i];
			if (strcmp(name, "auto") == 0) {
				solver = SM_MODES_AUTO;
			} else if (strcmp(name, "dense") == 0) {
				solver = SM_MODES_DENSE;
			} else if (strcmp(name, "sparse") == 0) {
				solver = SM_MODES_SPARSE;
			} else {
				cli_shown shown = {0};
				fprintf(stderr, "springmass modes: --solver: unknown solver '%s' (auto, dense, sparse)\n",
				        cli_shown_text(&shown, name));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if (strcmp(a, "--set") == 0 && has_value) {
			settings[setting_count++] = argv[++i];
		} else if (cli_model_argument("modes", a, &model_path) != 0) {
			usage(stderr);
			free(settings);
			return 2;
		}
	}
	if (cli_model_given("modes", model_path) != 0) {
		usage(stderr);
		free(settings);
		return 2;
	}
	if (cli_check_output("modes", "-o", csv_path, model_path, "the model file", false) != 0 ||
	    cli_check_folder_option("modes", "--vtk", vtk_dir) != 0 ||
	    cli_check_outputs_apart("modes", "-o", csv_path, "--vtk", vtk_dir) != 0) {
		free(settings);
		return 2;
	}
	if (cli_check_output_place("modes", "-o", csv_path, false) != 0 ||
	    cli_check_output_place("modes", "--vtk", vtk_dir, true) != 0) {
		free(settings);
		return 1;
	}

	int status = 1;
	sm_error err;
	cli_outputs outputs = {"modes", 0, 0, NULL, false};
	sm_model* model = NULL;
	double* x = NULL;
	sm_modes modes;
	memset(&modes, 0, sizeof modes);
	sm_document* doc = NULL;
	if ((status = cli_load_model("modes", model_path, settings, setting_count, &doc, &model)) != 0 ||
	    (status = cli_check_output_not_mesh_file("modes", "-o", csv_path, doc)) != 0)
		goto done;
	status = 1;
	const int32_t n = sm_model_particle_count(model);
	// The library's automatic choice falls back to the dense eigensolver for all modes or more
	// than the sparse one can give; above CLI_DENSE_LIMIT that runs for minutes to hours, so the
	// tool asks for fewer modes or an explicit --solver dense instead.
	const size_t dof = 3 * (size_t)sm_model_free_count(model);
	const size_t sparse_most = dof >= SM_MODES_SPARSE_MARGIN ? (dof - SM_MODES_SPARSE_MARGIN) / 4 : 0;
	if (solver == SM_MODES_AUTO && dof > CLI_DENSE_LIMIT && (count == 0 || (size_t)count > sparse_most)) {
		fprintf(
		    stderr,
		    "springmass modes: %s of %zu degrees of freedom need the dense eigensolver, whose time grows as "
		    "the cube of their number (minutes above %d, hours at 10000): ask for the lowest N modes with "
		    "-n N (the sparse solver, N <= %zu here), or give --solver dense to wait for it\n",
		    count == 0 ? "all the modes" : "that many modes", dof, CLI_DENSE_LIMIT, sparse_most);
		status = 2;
		goto done;
	}
	// --solver sparse asked for what it cannot give: a usage error, refused before the work.
	if (solver == SM_MODES_SPARSE && dof > 0 && (count == 0 || (size_t)count > sparse_most)) {
		if (sparse_most == 0)
			fprintf(
			    stderr,
			    "springmass modes: --solver sparse needs at least %d free degrees of freedom, the model has "
			    "%zu: use --solver dense\n",
			    SM_MODES_SPARSE_MARGIN + 4, dof);
		else
			fprintf(
			    stderr,
			    "springmass modes: --solver sparse gives the lowest modes, 1 to (dof - %d) / 4 = %zu of this "
			    "model's %zu degrees of freedom, not %s: use --solver dense\n",
			    SM_MODES_SPARSE_MARGIN, sparse_most, dof, count == 0 ? "all of them (-n 0)" : "that many");
		status = 2;
		goto done;
	}
	if (solver == SM_MODES_DENSE)
		cli_note_dense("modes", dof);
	x = malloc((3 * (size_t)n + 1) * sizeof(double));
	if (x == NULL) {
		fprintf(stderr, "springmass modes: out of memory\n");
		goto done;
	}
	if (at_equilibrium) {
		sm_statics_def statics = sm_default_statics_def();
		sm_statics_result res;
		if (cli_statics_solve("springmass modes: static equilibrium", false, model, &statics, x, NULL, &res,
		                      &err) != SM_OK) {
			cli_shown shown = {0};
			fprintf(stderr, "springmass modes: %s: ", cli_shown_path(&shown, model_path));
			cli_shown_free(&shown);
			cli_write_named(stderr, doc, model, err.message);
			fputc('\n', stderr);
			goto done;
		}
		printf("linearised about the static equilibrium (%d iterations, residual %.3e N)\n",
		       (int)res.iterations, res.residual);
	} else {
		sm_model_initial_state(model, x, NULL);
		printf("linearised about the initial configuration\n");
	}
	sm_modes_def def = sm_default_modes_def();
	def.configuration = x;
	def.mode_count = (int32_t)count;
	def.solver = solver;
	def.zero_tolerance = zero_tolerance;
	if (cli_modes_compute("springmass modes", model, &def, &modes, &err) != SM_OK) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass modes: %s: ", cli_shown_path(&shown, model_path));
		cli_shown_free(&shown);
		cli_write_named(stderr, doc, model, cli_without_prefix(err.message, "modes: "));
		fputc('\n', stderr);
		goto done;
	}
	printf("model             %s (%d particles, %d degrees of freedom)\n", sm_document_name(doc), (int)n,
	       (int)modes.dof);
	if (modes.dof == 0)
		printf("no free particle: nothing vibrates\n");
	else
		print_modes(&modes, at_equilibrium, steps_per_period, zero_tolerance);
	if (csv_path != NULL) {
		if (write_csv(&outputs, csv_path, doc, &modes) != 0)
			goto done;
	}
	// Every output is written, then all are moved to their places: none is left half-written, or
	// replaced, when another fails. Neither the model file nor the CSV is one of the mode files,
	// whose count is known now (checked before the folder is made or a mode written; a refusal
	// removes the CSV's temporary).
	if (vtk_dir != NULL) {
		char path[4096];
		for (int32_t m = 0; m < modes.count; m++) {
			if (!mode_path(path, sizeof path, vtk_dir, m))
				goto done;
			if (cli_check_folder_file("modes", vtk_dir, path, model_path) != 0 ||
			    cli_check_outputs_apart("modes", "-o", csv_path, "--vtk's file", path) != 0) {
				status = 2;
				goto done;
			}
		}
		if (cli_make_directory("modes", vtk_dir) != 0)
			goto done;
		for (int32_t m = 0; m < modes.count; m++)
			if (!mode_path(path, sizeof path, vtk_dir, m) ||
			    write_mode_vtk(&outputs, path, model, x, modes.shapes + (size_t)m * 3 * (size_t)n, (int)m + 1,
			                   modes.frequency[m], modes.omega_squared[m]) != 0)
				goto done;
	}
	if (cli_outputs_commit(&outputs) != 0)
		goto done;
	long removed = 0;
	if (vtk_dir != NULL) {
		char prefix[4096];
		if ((size_t)snprintf(prefix, sizeof prefix, "%s/mode_", vtk_dir) < sizeof prefix)
			removed = cli_remove_series_tail(prefix, 0, (long)modes.count + 1, ".vtk", CLI_LEGACY_VTK_HEADER);
	}
	{
		cli_shown shown = {0};
		const char* vtk_shown = vtk_dir != NULL ? cli_shown_path(&shown, vtk_dir) : NULL;
		if (csv_path != NULL)
			printf("mode shapes written to %s%s\n", cli_shown_path(&shown, csv_path),
			       modes.count > 0 ? "" : " (no modes: the particles only)");
		if (vtk_dir != NULL && modes.count > 0)
			printf("mode shapes written to %s/mode_<k>.vtk, k = 1 to %d (open them in ParaView)\n", vtk_shown,
			       (int)modes.count);
		else if (vtk_dir != NULL)
			printf("no mode shapes to write to %s\n", vtk_shown);
		if (removed == 1)
			printf("removed %s/mode_%d.vtk, left there by an earlier run with more modes\n", vtk_shown,
			       (int)modes.count + 1);
		else if (removed > 1)
			printf("removed %s/mode_%d.vtk to mode_%ld.vtk, left there by an earlier run with more modes\n",
			       vtk_shown, (int)modes.count + 1, (long)modes.count + removed);
		cli_shown_free(&shown);
	}
	status = 0;
done:
	cli_outputs_discard(&outputs);
	sm_modes_release(&modes);
	free(x);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	free(settings);
	return status;
}

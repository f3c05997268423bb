// springmass statics: the static equilibrium of a model file.
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

// The library's messages name the fields of sm_statics_def the options set: in place, each becomes
// the option the user typed ("no equilibrium found in 3 iterations (--max-iterations)",
// "--tolerance 100 N is not below the largest load ...").
static void name_options(char message[SM_ERROR_MESSAGE_CAPACITY])
{
	static const char* const names[][2] = {{"max_iterations", "--max-iterations"},
	                                       {"residual_tolerance", "--tolerance"}};
	for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
		char* at = strstr(message, names[k][0]);
		if (at == NULL)
			continue;
		const size_t field = strlen(names[k][0]), option = strlen(names[k][1]);
		const size_t tail = strlen(at + field) + 1;
		// The option is no longer than the field, or there is room: the text after moves.
		if ((size_t)(at - message) + option + tail > SM_ERROR_MESSAGE_CAPACITY)
			continue;
		memmove(at + option, at + field, tail);
		memcpy(at, names[k][1], option);
	}
}

static void usage(FILE* out)
{
	fprintf(out,
	        "usage: springmass statics MODEL [options]\n"
	        "\n"
	        "Finds where the model comes to rest under gravity, its constant loads and its fixed\n"
	        "particles (\"fixed\": true, held at their initial positions; a motion port's particle\n"
	        "is free here, as in springmass run): Newton's method on the force balance with the\n"
	        "exact stiffness and a line search on the potential energy.\n"
	        "Prints the iterations, the residual force, the particle nearest to its tolerance, whether\n"
	        "the rest shape is stable and the reaction force at every fixed particle. A progress line\n"
	        "goes to stderr for solves longer than a second.\n"
	        "\n"
	        "options:\n"
	        "  -o, --output FILE      write the rest shape as CSV: particle, name, position [m],\n"
	        "                         displacement from the initial position [m], reaction [N]\n"
	        "  --vtk DIR              write DIR/statics.vtk (ParaView: particles, springs as lines,\n"
	        "                         displacement and reaction vectors)\n"
	        "  --save-model FILE      save the model with the rest shape as its initial positions\n"
	        "                         (a cloth that starts hanging at rest)\n"
	        "  --set NAME=VALUE       change a parameter of the model file first (repeatable)\n"
	        "  --tolerance F          largest force left on any free particle [N], below the largest\n"
	        "                         load on one (default: at each particle 1e-9, or 1e-6 of its\n"
	        "                         own weight and load if smaller)\n"
	        "  --max-iterations N     Newton iterations allowed (default 500)\n"
	        "  --solver NAME          auto (default), dense (GSL) or sparse (CHOLMOD)\n"
	        "  -q, --quiet            print the summary only, not every reaction, and no progress line\n"
	        "  -h, --help             this text\n"
	        "\n"
	        "Exit status: 0 when an equilibrium is found (stable or not, as printed), 1 for a bad model,\n"
	        "no equilibrium or an output that cannot be written, 2 for a usage error (also a --tolerance\n"
	        "at or above the largest load on a free particle).\n");
}

// Legacy VTK polydata: particles as points, springs as lines, displacement and reaction fields.
static int write_vtk(cli_outputs* outputs, const char* path, const sm_model* model, const double* x,
                     const double* displacement, const double* reactions)
{
	FILE* f = cli_vtk_open(outputs, "statics", path, "springmass static equilibrium", model, x);
	if (f == NULL)
		return -1;
	const int32_t n = sm_model_particle_count(model);
	cli_vtk_vectors(f, "displacement", n, displacement, true);
	cli_vtk_vectors(f, "reaction", n, reactions, false);
	return cli_close("statics", path, f);
}

static int write_csv(cli_outputs* outputs, const char* path, const sm_document* doc, int32_t n,
                     const double* x, const double* x0, const double* reactions)
{
	FILE* f = cli_outputs_open(outputs, path);
	if (f == NULL)
		return -1;
	fprintf(f, "particle,name,x,y,z,dx,dy,dz,reaction_x,reaction_y,reaction_z\n");
	for (int32_t i = 0; i < n; i++) {
		const char* name = sm_document_particle_name(doc, i);
		fprintf(f, "%d,", (int)i);
		cli_csv_field(f, "", name != NULL ? name : "", "");
		for (int c = 0; c < 3; c++)
			cli_csv_number(f, x[3 * i + c]);
		for (int c = 0; c < 3; c++)
			cli_csv_number(f, x[3 * i + c] - x0[3 * i + c]);
		for (int c = 0; c < 3; c++)
			cli_csv_number(f, reactions[3 * i + c]);
		fprintf(f, "\n");
	}
	return cli_close("statics", path, f);
}

int sm_cmd_statics(int argc, char** argv)
{
	const char* model_path = NULL;
	const char* csv_path = NULL;
	const char* vtk_dir = NULL;
	const char* save_path = NULL;
	const char** settings = calloc((size_t)argc + 1, sizeof *settings);
	int setting_count = 0;
	int quiet = 0;
	sm_statics_def def = sm_default_statics_def();
	if (settings == NULL)
		return 1;
	for (int i = 1; i < argc; i++) {
		const char* a = argv[i];
		const int has_value = i + 1 < argc;
		if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
			usage(stdout);
			free(settings);
			return 0;
		} else if ((strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) && has_value) {
			csv_path = argv[++i];
		} else if (strcmp(a, "--vtk") == 0 && has_value) {
			vtk_dir = argv[++i];
		} else if (strcmp(a, "--save-model") == 0 && has_value) {
			save_path = argv[++i];
		} else if (strcmp(a, "--set") == 0 && has_value) {
			settings[setting_count++] = argv[++i];
		} else if (strcmp(a, "--tolerance") == 0 && has_value) {
			if (!cli_parse_number(argv[++i], &def.residual_tolerance) || !(def.residual_tolerance > 0.0)) {
				cli_shown shown = {0};
				fprintf(
				    stderr,
				    "springmass statics: --tolerance needs a positive finite number of newtons, got '%s'\n",
				    cli_shown_text(&shown, argv[i]));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if (strcmp(a, "--max-iterations") == 0 && has_value) {
			long v;
			if (!cli_parse_count(argv[++i], 1, 1000000, &v)) {
				cli_shown shown = {0};
				fprintf(stderr,
				        "springmass statics: --max-iterations needs a count from 1 to 1000000, got '%s'\n",
				        cli_shown_text(&shown, argv[i]));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
			def.max_iterations = (int32_t)v;
		} else if (strcmp(a, "--solver") == 0 && has_value) {
			const char* s = argv[++i];
			if (strcmp(s, "auto") == 0)
				def.solver = SM_STATICS_AUTO;
			else if (strcmp(s, "dense") == 0)
				def.solver = SM_STATICS_DENSE;
			else if (strcmp(s, "sparse") == 0)
				def.solver = SM_STATICS_SPARSE;
			else {
				cli_shown shown = {0};
				fprintf(stderr, "springmass statics: --solver: unknown solver '%s' (auto, dense, sparse)\n",
				        cli_shown_text(&shown, s));
				cli_shown_free(&shown);
				free(settings);
				return 2;
			}
		} else if (strcmp(a, "-q") == 0 || strcmp(a, "--quiet") == 0) {
			quiet = 1;
		} else if (cli_model_argument("statics", a, &model_path) != 0) {
			usage(stderr);
			free(settings);
			return 2;
		}
	}
	if (cli_model_given("statics", model_path) != 0) {
		usage(stderr);
		free(settings);
		return 2;
	}
	if (cli_check_output("statics", "-o", csv_path, model_path, "the model file", false) != 0 ||
	    cli_check_output("statics", "--save-model", save_path, model_path, "the model file", false) != 0 ||
	    cli_check_folder_option("statics", "--vtk", vtk_dir) != 0) {
		free(settings);
		return 2;
	}
	// The VTK file's name, and no two outputs one file.
	char vtk_path[4096];
	if (vtk_dir != NULL &&
	    (size_t)snprintf(vtk_path, sizeof vtk_path, "%s/statics.vtk", vtk_dir) >= sizeof vtk_path) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass statics: path too long: %s\n", cli_shown_path(&shown, vtk_dir));
		cli_shown_free(&shown);
		free(settings);
		return 2;
	}
	const char* vtk_file = vtk_dir != NULL ? vtk_path : NULL;
	if ((vtk_file != NULL && cli_check_folder_file("statics", vtk_dir, vtk_file, model_path) != 0) ||
	    cli_check_outputs_apart("statics", "-o", csv_path, "--save-model", save_path) != 0 ||
	    cli_check_outputs_apart("statics", "-o", csv_path, "--vtk's file", vtk_file) != 0 ||
	    cli_check_outputs_apart("statics", "-o", csv_path, "--vtk", vtk_dir) != 0 ||
	    cli_check_outputs_apart("statics", "--save-model", save_path, "--vtk", vtk_dir) != 0 ||
	    cli_check_outputs_apart("statics", "--save-model", save_path, "--vtk's file", vtk_file) != 0) {
		free(settings);
		return 2;
	}
	if (cli_check_output_place("statics", "-o", csv_path, false) != 0 ||
	    cli_check_output_place("statics", "--vtk", vtk_dir, true) != 0 ||
	    cli_check_output_place("statics", "--save-model", save_path, false) != 0) {
		free(settings);
		return 1;
	}

	int status = 1;
	sm_error err;
	cli_outputs outputs = {"statics", 0, 0, NULL, false};
	char* saved_model = NULL;
	sm_model* model = NULL;
	double *x0 = NULL, *x = NULL, *reactions = NULL, *displacement = NULL;
	sm_document* doc = NULL;
	if ((status = cli_load_model("statics", model_path, settings, setting_count, &doc, &model)) != 0 ||
	    (status = cli_check_output_not_mesh_file("statics", "-o", csv_path, doc)) != 0 ||
	    (status = cli_check_output_not_mesh_file("statics", "--save-model", save_path, doc)) != 0 ||
	    (status = cli_check_output_not_mesh_file("statics", "--vtk's file", vtk_file, doc)) != 0)
		goto done;
	status = 1;
	const int32_t n = sm_model_particle_count(model);
	const size_t n3 = 3 * (size_t)n + 1;
	x0 = malloc(n3 * sizeof(double));
	x = malloc(n3 * sizeof(double));
	reactions = malloc(n3 * sizeof(double));
	displacement = malloc(n3 * sizeof(double));
	if (x0 == NULL || x == NULL || reactions == NULL || displacement == NULL) {
		fprintf(stderr, "springmass statics: out of memory\n");
		goto done;
	}
	sm_model_initial_state(model, x0, NULL);
	if (def.solver == SM_STATICS_DENSE)
		cli_note_dense("statics", 3 * (size_t)sm_model_free_count(model));
	sm_statics_result res;
	const sm_status st =
	    cli_statics_solve("springmass statics", quiet, model, &def, x, reactions, &res, &err);
	if (st != SM_OK) {
		// The options are checked above: the one value the library still refuses is a --tolerance
		// at or above the largest load, which any shape would meet. Like every other value refused,
		// it is a usage error.
		if (st == SM_ERROR_INVALID_ARGUMENT)
			status = 2;
		cli_shown shown = {0};
		fprintf(stderr, "springmass statics: %s: ", cli_shown_path(&shown, model_path));
		cli_shown_free(&shown);
		name_options(err.message);
		cli_write_named(stderr, doc, model, cli_without_prefix(err.message, "statics: "));
		fputc('\n', stderr);
		goto done;
	}
	for (size_t k = 0; k + 1 < n3; k++)
		displacement[k] = x[k] - x0[k];

	const sm_model_def md = sm_model_get_def(model);
	const double mass = sm_model_total_mass(model);
	double largest = 0.0;
	int32_t largest_at = -1;
	for (int32_t i = 0; i < n; i++) {
		const double* d = displacement + 3 * i;
		const double m = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
		if (m > largest) {
			largest = m;
			largest_at = i;
		}
	}
	const int32_t springs = sm_model_spring_count(model);
	printf("model            %s (%d particle%s, %d free, %d spring%s)\n", sm_document_name(doc), (int)n,
	       n == 1 ? "" : "s", (int)sm_model_free_count(model), (int)springs, springs == 1 ? "" : "s");
	printf("solver           %s, %d iteration%s\n",
	       res.solver == SM_STATICS_SPARSE ? "sparse Cholesky (CHOLMOD)" : "dense modified Cholesky (GSL)",
	       (int)res.iterations, res.iterations == 1 ? "" : "s");
	printf("residual         %.3e N (tolerance %.3e N)\n", res.residual, res.tolerance);
	// Each particle is balanced to its own tolerance: the line above gives the largest force and
	// the loosest tolerance, this one the particle nearest to its own (a light part's particle in a
	// model with heavy ones, whose tolerance is far below the loosest).
	char line[256];
	if (res.critical_particle >= 0) {
		snprintf(line, sizeof line,
		         "balance          particle %d nearest to its tolerance: %.3e N of %.3e N\n",
		         (int)res.critical_particle, res.critical_residual, res.critical_tolerance);
		cli_write_named(stdout, doc, model, line);
	}
	// Where a rest-length spring has its two particles at one point the balance holds only by the
	// convention that such a spring exerts no force (model.h): not a saddle or a mechanism but a
	// maximum of that spring's energy, which `modes` refuses to linearise.
	const int32_t coincident = res.coincident_spring;
	if (res.stable)
		printf("stable           yes (a minimum of the potential energy)\n");
	else if (coincident < 0)
		printf(
		    "stable           no (a saddle point or a free mechanism: see `springmass modes --at-equilibrium`)\n");
	else {
		char stable_line[256];
		snprintf(
		    stable_line, sizeof stable_line,
		    "stable           no (spring %d has its two particles at one point: a force balance only by the "
		    "convention that it exerts no force there, at a maximum of its energy)\n",
		    (int)coincident);
		cli_write_named(stdout, doc, model, stable_line);
	}
	printf("potential energy %.9g J\n", res.potential_energy);
	if (largest_at >= 0) {
		snprintf(line, sizeof line, "largest motion   %.6g m at particle %d\n", largest, (int)largest_at);
		cli_write_named(stdout, doc, model, line);
	}
	// Statics treats every spring as intact; say so when the equilibrium stretches one to its
	// break strain or beyond (a simulation would break it: the same test, L >= l0 (1 + strain)).
	int32_t beyond = 0, worst = -1;
	double worst_ratio = 0.0;
	for (int32_t k = 0; k < sm_model_spring_count(model); k++) {
		sm_spring_def sd;
		if (sm_model_get_spring(model, k, &sd) != SM_OK || !isfinite(sd.break_strain) ||
		    !sm_model_spring_enabled(model, k) || !(sd.rest_length > 0.0))
			continue;
		const double* a = x + 3 * (size_t)sd.a;
		const double* b = x + 3 * (size_t)sd.b;
		const double d0 = b[0] - a[0], d1 = b[1] - a[1], d2 = b[2] - a[2];
		const double length = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
		if (length - sd.rest_length * (1.0 + sd.break_strain) >= 0.0) {
			const double strain = length / sd.rest_length - 1.0;
			beyond++;
			if (worst < 0 || strain / sd.break_strain > worst_ratio) {
				worst_ratio = strain / sd.break_strain;
				worst = k;
			}
		}
	}
	if (beyond > 0) {
		snprintf(
		    line, sizeof line,
		    "break strains    %d spring(s) at or beyond theirs, which a simulation would break; the furthest, at %.3g "
		    "times its break strain: spring %d\n",
		    (int)beyond, worst_ratio, (int)worst);
		cli_write_named(stdout, doc, model, line);
	}
	printf("weight           (%.9g, %.9g, %.9g) N\n", mass * md.gravity[0], mass * md.gravity[1],
	       mass * md.gravity[2]);
	// The particles' loads, which the reactions balance with the weight.
	double loads[3];
	if (cli_total_load(model, loads) > 0)
		printf("loads            (%.9g, %.9g, %.9g) N\n", loads[0], loads[1], loads[2]);
	printf("reactions, sum   (%.9g, %.9g, %.9g) N\n", res.reaction_total[0], res.reaction_total[1],
	       res.reaction_total[2]);
	if (!quiet) {
		int header = 0;
		for (int32_t i = 0; i < n; i++) {
			if (sm_model_free_index(model, i) >= 0)
				continue;
			if (!header) {
				printf("\n%-10s %-20s %16s %16s %16s\n", "particle", "name", "reaction x [N]",
				       "reaction y [N]", "reaction z [N]");
				header = 1;
			}
			const char* name = sm_document_particle_name(doc, i);
			printf("%-10d ", (int)i);
			cli_write_text(stdout, name != NULL ? name : "", 20);
			printf(" %16.9g %16.9g %16.9g\n", reactions[3 * i], reactions[3 * i + 1], reactions[3 * i + 2]);
		}
	}
	// Every output is written, then all are moved to their places: none is left half-written, or
	// replaced, when another fails.
	if (csv_path != NULL && write_csv(&outputs, csv_path, doc, n, x, x0, reactions) != 0)
		goto done;
	if (vtk_dir != NULL && (cli_make_directory("statics", vtk_dir) != 0 ||
	                        write_vtk(&outputs, vtk_path, model, x, displacement, reactions) != 0))
		goto done;
	if (save_path != NULL) {
		FILE* f = NULL;
		if (sm_document_set_initial_state(doc, x, NULL, &err) != SM_OK ||
		    (saved_model = sm_document_to_json(doc, &err)) == NULL) {
			fprintf(stderr, "springmass statics: %s\n", err.message);
			goto done;
		}
		if ((f = cli_outputs_open(&outputs, save_path)) == NULL)
			goto done;
		fputs(saved_model, f);
		if (cli_close("statics", save_path, f) != 0)
			goto done;
	}
	if (cli_outputs_commit(&outputs) != 0)
		goto done;
	{
		cli_shown shown = {0};
		if (csv_path != NULL)
			printf("\nrest shape written to %s\n", cli_shown_path(&shown, csv_path));
		if (vtk_dir != NULL)
			printf("rest shape written to %s (open it in ParaView)\n", cli_shown_path(&shown, vtk_path));
		if (save_path != NULL)
			printf("model starting at rest saved to %s\n", cli_shown_path(&shown, save_path));
		cli_shown_free(&shown);
	}
	status = 0;
done:
	cli_outputs_discard(&outputs);
	free(saved_model);
	free(x0);
	free(x);
	free(reactions);
	free(displacement);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	free(settings);
	return status;
}

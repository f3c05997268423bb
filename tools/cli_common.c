// Helpers shared by the subcommands.
#define _XOPEN_SOURCE 700  // realpath

#include "cli_common.h"
#include "cli_signals.h"

#include "springmass/analysis.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

// The grammar is checked by hand because strtod also reads hexadecimal, infinities, NaN and
// leading spaces; once it holds, strtod gives the correctly rounded double (in the C locale,
// which the tool never changes).
bool cli_parse_number(const char* text, double* value)
{
	const char* c = text;
	if (*c == '+' || *c == '-')
		c++;
	int digits = 0;
	for (; *c >= '0' && *c <= '9'; c++)
		digits++;
	if (*c == '.')
		for (c++; *c >= '0' && *c <= '9'; c++)
			digits++;
	if (digits == 0)
		return false;
	if (*c == 'e' || *c == 'E') {
		c++;
		if (*c == '+' || *c == '-')
			c++;
		if (!(*c >= '0' && *c <= '9'))
			return false;
		while (*c >= '0' && *c <= '9')
			c++;
	}
	if (*c != '\0')
		return false;
	const double v = strtod(text, NULL);
	if (!isfinite(v))
		return false;
	*value = v;
	return true;
}

bool cli_parse_count(const char* text, double min, double max, long* value)
{
	double v;
	if (!cli_parse_number(text, &v) || !(v >= min && v <= max) || v != floor(v))
		return false;
	// A count that reads as 0 only by underflow (1e-400) is not 0.
	for (const char* c = text; v == 0.0 && *c != '\0' && *c != 'e' && *c != 'E'; c++)
		if (*c >= '1' && *c <= '9')
			return false;
	*value = (long)v;
	return true;
}

// Copies the NAME of "NAME=VALUE" into name (NUL-terminated) and returns its length: 0 if there
// is no '=' or no name, `size` if the name does not fit (name is then left as it was).
static size_t setting_name(const char* setting, char* name, size_t size)
{
	const char* eq = strchr(setting, '=');
	const size_t length = eq ? (size_t)(eq - setting) : 0;
	if (length == 0 || length >= size)
		return length == 0 ? 0 : size;
	memcpy(name, setting, length);
	name[length] = '\0';
	return length;
}

int32_t cli_setting_parameter(const sm_document* doc, const char* setting)
{
	char name[256];
	const size_t length = setting_name(setting, name, sizeof name);
	return length == 0 || length == sizeof name ? -1 : sm_document_parameter_index(doc, name);
}

// NAME=VALUE of --set: the parameter's index and the value, or a message and the exit status.
static int parse_setting(const char* command, const sm_document* doc, const char* setting, int32_t* index,
                         double* value)
{
	char name[256];
	const size_t length = setting_name(setting, name, sizeof name);
	cli_shown shown = {0};
	if (length == 0) {
		fprintf(stderr, "springmass %s: --set expects NAME=VALUE, got '%s'\n", command,
		        cli_shown_text(&shown, setting));
		cli_shown_free(&shown);
		return 2;
	}
	if (length == sizeof name) {
		fprintf(stderr, "springmass %s: --set %s: the parameter's name is too long (255 bytes at most)\n",
		        command, cli_shown_text(&shown, setting));
		cli_shown_free(&shown);
		return 2;
	}
	const char* eq = setting + length;
	if (!cli_parse_number(eq + 1, value)) {
		fprintf(stderr, "springmass %s: --set %s: '%s' is not a finite number\n", command,
		        cli_shown_text(&shown, setting), cli_shown_text(&shown, eq + 1));
		cli_shown_free(&shown);
		return 2;
	}
	*index = sm_document_parameter_index(doc, name);
	if (*index < 0) {
		fprintf(stderr, "springmass %s: --set %s: the model has no parameter named \"%s\"\n", command,
		        cli_shown_text(&shown, setting), cli_shown_text(&shown, name));
		cli_shown_free(&shown);
		return 1;
	}
	return 0;
}

// All settings at once (sm_document_set_parameters), as if the file gave these values: a rope's
// new start and end are taken in either order; a parameter set twice takes the last value.
int cli_set_parameters(const char* command, sm_document* doc, const char* const* settings, int count)
{
	const int32_t np = sm_document_parameter_count(doc);
	double* values = malloc(((size_t)np + 1) * sizeof(double));
	if (values == NULL) {
		fprintf(stderr, "springmass %s: out of memory\n", command);
		return 1;
	}
	for (int32_t k = 0; k < np; k++)
		values[k] = sm_document_parameter_value(doc, k);
	for (int k = 0; k < count; k++) {
		int32_t index;
		double value;
		const int status = parse_setting(command, doc, settings[k], &index, &value);
		if (status != 0) {
			free(values);
			return status;
		}
		values[index] = value;
	}
	sm_error err;
	const sm_status st = sm_document_set_parameters(doc, values, &err);
	free(values);
	if (st != SM_OK) {
		fprintf(stderr, "springmass %s: ", command);
		for (int k = 0; k < count; k++)
			fprintf(stderr, "--set %s%s", settings[k], k + 1 < count ? " " : ": ");
		fprintf(stderr, "%s\n", err.message);
		return 1;
	}
	return 0;
}

void cli_write_text(FILE* f, const char* text, int width)
{
	char* shown = malloc(SM_TERMINAL_TEXT_CAPACITY(strlen(text)));
	if (shown != NULL)
		sm_text_for_terminal(shown, text);
	fputs(shown != NULL ? shown : "(out of memory)", f);
	// Characters, not bytes: those of UTF-8 are the bytes that begin one.
	int characters = 0;
	for (const char* c = shown != NULL ? shown : ""; *c != '\0'; c++)
		characters += ((unsigned char)*c & 0xc0) != 0x80;
	for (; characters < width; characters++)
		fputc(' ', f);
	free(shown);
}

// Writes particle `index` by its name in the file, or by its index where it has none.
static void write_particle_name(FILE* f, const sm_document* doc, int32_t index)
{
	const char* name = sm_document_particle_name(doc, index);
	if (name != NULL)
		cli_write_text(f, name, 0);
	else
		fprintf(f, "particle %d", (int)index);
}

// Reads the decimal index at *text into *index and moves past it; false (nothing moved) if there
// is none, it is out of range, or it is the start of another number or word ("1.5", "1e3",
// "2x"; a full stop after it ends a sentence).
static bool read_index(const char** text, int32_t count, int32_t* index)
{
	const char* s = *text;
	long value = 0;
	if (*s < '0' || *s > '9')
		return false;
	for (; *s >= '0' && *s <= '9'; s++)
		if ((value = 10 * value + (*s - '0')) >= count)
			return false;
	if ((*s == '.' && s[1] >= '0' && s[1] <= '9') || (*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
	    *s == '_')
		return false;
	*index = (int32_t)value;
	*text = s;
	return true;
}

const char* cli_without_prefix(const char* message, const char* prefix)
{
	const size_t length = strlen(prefix);
	return strncmp(message, prefix, length) == 0 ? message + length : message;
}

void cli_write_named(FILE* f, const sm_document* doc, const sm_model* model, const char* message)
{
	const int32_t particles = sm_model_particle_count(model), springs = sm_model_spring_count(model);
	const char* s = message;
	while (*s != '\0') {
		// A word "particle", "particles" or "spring" at a word's start, a space, an index.
		const bool word_start = s == message || !((s[-1] >= 'a' && s[-1] <= 'z') || s[-1] == '_');
		const size_t word = !word_start                         ? 0
		                    : strncmp(s, "particles ", 10) == 0 ? 10
		                    : strncmp(s, "particle ", 9) == 0   ? 9
		                    : strncmp(s, "spring ", 7) == 0     ? 7
		                                                        : 0;
		int32_t index;
		const char* after = s + word;
		if (word == 0 || !read_index(&after, word == 7 ? springs : particles, &index)) {
			fputc(*s++, f);
			continue;
		}
		fwrite(s, 1, (size_t)(after - s), f);
		if (word == 7) {
			sm_spring_def def;
			sm_model_get_spring(model, index, &def);
			fputs(" (between ", f);
			write_particle_name(f, doc, def.a);
			fputs(" and ", f);
			write_particle_name(f, doc, def.b);
			fputc(')', f);
			s = after;
			continue;
		}
		// Particles: this index and, after "particles", those that follow (", 5", " and 6").
		for (;;) {
			const char* name = sm_document_particle_name(doc, index);
			if (name != NULL) {
				fputs(" (", f);
				cli_write_text(f, name, 0);
				fputc(')', f);
			}
			s = after;
			if (word != 10)
				break;
			const size_t gap = strncmp(s, ", ", 2) == 0 ? 2 : strncmp(s, " and ", 5) == 0 ? 5 : 0;
			after = s + gap;
			if (gap == 0 || !read_index(&after, particles, &index))
				break;
			fwrite(s, 1, (size_t)(after - s), f);
		}
	}
}

int cli_load_model(const char* command, const char* path, const char* const* settings, int count,
                   sm_document** doc, sm_model** model)
{
	*model = NULL;
	sm_error err;
	*doc = sm_document_load(path, &err);
	if (*doc == NULL) {
		fprintf(stderr, "springmass %s: %s\n", command, err.message);
		return 1;
	}
	int status = cli_set_parameters(command, *doc, settings, count);
	if (status == 0 && sm_document_build(*doc, model, &err) != SM_OK) {
		fprintf(stderr, "springmass %s: %s\n", command, err.message);
		status = 1;
	}
	if (status != 0) {
		sm_document_destroy(*doc);
		*doc = NULL;
		*model = NULL;
	}
	return status;
}

void cli_note_dense(const char* command, size_t dof)
{
	if (dof > CLI_DENSE_LIMIT)
		fprintf(
		    stderr,
		    "springmass %s: note: a dense solve of %zu degrees of freedom takes long (its time grows as the "
		    "cube of their number: minutes above %d, hours at 10000)\n",
		    command, dof, CLI_DENSE_LIMIT);
}

bool cli_warn_coarse_tolerances(FILE* f, const char* prefix, const sm_model* model,
                                const sm_simulation_def* def)
{
	sm_motion_scales scales;
	if (sm_model_motion_scales(model, &scales) != SM_OK || !sm_tolerances_coarse(def, &scales))
		return false;
	fprintf(f,
	        "%sthe absolute tolerances, %g m and %g m/s, are coarse for this model: its shortest spring is "
	        "%.3g m and moves at up to %.3g m/s at its highest frequency, so its motion is resolved only to "
	        "them (about 1e-8 of these scales: atol_position %.1g m, atol_velocity %.1g m/s)\n",
	        prefix, def->absolute_tolerance_position, def->absolute_tolerance_velocity, scales.length,
	        scales.speed, 1e-8 * scales.length, 1e-8 * scales.speed);
	return true;
}

bool cli_warn_tight_tolerances(FILE* f, const char* prefix, const sm_document* doc, const sm_model* model,
                               const sm_simulation_def* def)
{
	sm_round_off round_off;
	if (sm_model_round_off(model, &round_off) != SM_OK || !sm_tolerances_tight(def, &round_off))
		return false;
	char spring[32];
	snprintf(spring, sizeof spring, "spring %d", (int)round_off.spring);
	fprintf(f, "%sthe absolute tolerance of velocities, %g m/s, is too tight for the round-off of ", prefix,
	        def->absolute_tolerance_velocity);
	cli_write_named(f, doc, model, spring);
	fprintf(
	    f,
	    ", %g N/m: rounding its force moves its ends' velocities by up to %.2g m/s in a step, and CVODE's "
	    "steps fail over and over below a tenth of that (it may stop at max_steps; "
	    "atol_velocity %.2g m/s or more)\n",
	    round_off.stiffness, round_off.velocity, SM_TIGHT_TOLERANCE * round_off.velocity);
	return true;
}

long cli_output_rows(double t_end, double interval)
{
	const double ratio = t_end / interval;
	if (!(ratio <= CLI_MAX_ROWS))
		return -1;
	return ratio < 1.0 ? 1 : (long)ceil(ratio * (1.0 - 1e-9));
}

int cli_make_directory(const char* command, const char* dir)
{
	if (mkdir(dir, 0777) == 0)
		return 0;
	const int error = errno;
	struct stat st;
	if (error == EEXIST && stat(dir, &st) == 0 && S_ISDIR(st.st_mode))
		return 0;
	cli_shown shown = {0};
	if (error == EEXIST)
		fprintf(stderr, "springmass %s: cannot create directory %s: a file of that name exists\n", command,
		        cli_shown_path(&shown, dir));
	else
		fprintf(stderr, "springmass %s: cannot create directory %s: %s\n", command,
		        cli_shown_path(&shown, dir), strerror(error));
	cli_shown_free(&shown);
	return -1;
}

void cli_csv_field(FILE* f, const char* prefix, const char* text, const char* suffix)
{
	const char* const parts[3] = {prefix, text, suffix};
	bool quote = false;
	for (int k = 0; k < 3; k++)
		quote = quote || strpbrk(parts[k], ",\"") != NULL;
	if (quote)
		fputc('"', f);
	for (int k = 0; k < 3; k++)
		for (const char* c = parts[k]; *c != '\0'; c++) {
			if (*c == '"')
				fputc('"', f);
			fputc(*c, f);
		}
	if (quote)
		fputc('"', f);
}

void cli_csv_number(FILE* f, double value)
{
	char text[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(value, text);
	fprintf(f, ",%s", text);
}

void cli_vtk_points(FILE* f, int32_t n, const double* x)
{
	char text[3][SM_NUMBER_TEXT_CAPACITY];
	for (int32_t i = 0; i < n; i++) {
		for (int c = 0; c < 3; c++)
			sm_format_number(x[3 * (size_t)i + (size_t)c], text[c]);
		fprintf(f, "%s %s %s\n", text[0], text[1], text[2]);
	}
}

FILE* cli_vtk_open(cli_outputs* outputs, const char* command, const char* path, const char* title,
                   const sm_model* model, const double* x)
{
	FILE* f = outputs != NULL ? cli_outputs_open(outputs, path) : fopen(path, "w");
	if (f == NULL) {
		if (outputs == NULL)
			cli_cannot_write(command, path);
		return NULL;
	}
	const int32_t n = sm_model_particle_count(model);
	const int32_t springs = sm_model_spring_count(model);
	int32_t intact = 0;
	for (int32_t s = 0; s < springs; s++)
		intact += sm_model_spring_enabled(model, s);
	fprintf(f, "# vtk DataFile Version 3.0\n%s\nASCII\nDATASET POLYDATA\nPOINTS %d double\n", title, (int)n);
	cli_vtk_points(f, n, x);
	// No LINES section without springs: VTK's legacy reader fails on "LINES 0 0" and drops the
	// point data after it.
	if (intact > 0)
		fprintf(f, "LINES %d %d\n", (int)intact, 3 * (int)intact);
	for (int32_t s = 0; s < springs; s++) {
		if (!sm_model_spring_enabled(model, s))
			continue;
		sm_spring_def d;
		sm_model_get_spring(model, s, &d);
		fprintf(f, "2 %d %d\n", (int)d.a, (int)d.b);
	}
	return f;
}

void cli_vtk_vectors(FILE* f, const char* name, int32_t count, const double* values, bool first)
{
	if (first)
		fprintf(f, "POINT_DATA %d\n", (int)count);
	fprintf(f, "VECTORS %s double\n", name);
	for (int32_t i = 0; i < count; i++)
		fprintf(f, "%.9g %.9g %.9g\n", values[3 * i], values[3 * i + 1], values[3 * i + 2]);
}

int cli_check_folder_option(const char* command, const char* option, const char* dir)
{
	if (dir == NULL || strcmp(dir, "-") != 0)
		return 0;
	fprintf(
	    stderr,
	    "springmass %s: %s -: this output is a folder of files, not standard output; give its name (./- for "
	    "a folder called -)\n",
	    command, option);
	return 2;
}

int cli_check_output(const char* command, const char* option, const char* output, const char* input,
                     const char* input_what, bool dash_is_stdout)
{
	if (output == NULL)
		return 0;
	if (strcmp(output, "-") == 0) {
		if (dash_is_stdout)
			return 0;
		fprintf(stderr, "springmass %s: %s -: this output is a file, not standard output; give its name\n",
		        command, option);
		return 2;
	}
	// Nor is it standard output under another name (/dev/stdout) where that is a file: the report
	// the command prints there would overwrite it.
	struct stat out, st;
	if (!dash_is_stdout && fstat(STDOUT_FILENO, &out) == 0 && S_ISREG(out.st_mode) &&
	    stat(output, &st) == 0 && st.st_dev == out.st_dev && st.st_ino == out.st_ino) {
		cli_shown shown = {0};
		fprintf(
		    stderr,
		    "springmass %s: %s %s is standard output, where the report goes; give the output its own file\n",
		    command, option, cli_shown_path(&shown, output));
		cli_shown_free(&shown);
		return 2;
	}
	if (input != NULL && cli_same_file(output, input)) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass %s: %s %s would overwrite %s %s, which it reads; give another name\n",
		        command, option, cli_shown_path(&shown, output), input_what, cli_shown_path(&shown, input));
		cli_shown_free(&shown);
		return 2;
	}
	return 0;
}

int cli_check_output_not_mesh_file(const char* command, const char* option, const char* output,
                                   const sm_document* doc)
{
	if (output == NULL || strcmp(output, "-") == 0)
		return 0;
	for (int32_t k = 0; k < sm_document_structure_count(doc); k++) {
		const char* path = sm_document_structure_file_path(doc, k);
		const bool same = path != NULL && cli_same_file(output, path);
		if (same) {
			cli_shown shown = {0};
			fprintf(stderr,
			        "springmass %s: %s %s would overwrite the OBJ file of the mesh %s (structures[%d].file), "
			        "which it reads; give another name\n",
			        command, option, cli_shown_path(&shown, output), sm_document_structure(doc, k).name,
			        (int)k);
			cli_shown_free(&shown);
			return 2;
		}
	}
	return 0;
}

int cli_check_folder_file(const char* command, const char* dir, const char* file, const char* model)
{
	if (!cli_same_file(file, model))
		return 0;
	cli_shown shown = {0};
	fprintf(stderr,
	        "springmass %s: --vtk %s: its file %s would overwrite the model file %s, which it reads; give "
	        "another folder\n",
	        command, cli_shown_path(&shown, dir), cli_shown_path(&shown, file),
	        cli_shown_path(&shown, model));
	cli_shown_free(&shown);
	return 2;
}

// The path a file has, or would have once created: its real path if it exists, else its
// folder's real path and its name (a folder's name may end in '/'); NULL if the folder cannot be
// found either (malloc'd).
static char* canonical_path(const char* path)
{
	char* real = realpath(path, NULL);
	if (real != NULL)
		return real;
	size_t length = strlen(path);
	while (length > 1 && path[length - 1] == '/')
		length--;
	char* trimmed = strndup(path, length);
	if (trimmed == NULL)
		return NULL;
	const char* slash = strrchr(trimmed, '/');
	const char* name = slash != NULL ? slash + 1 : trimmed;
	char* folder =
	    slash == NULL ? strdup(".") : strndup(trimmed, slash == trimmed ? 1 : (size_t)(slash - trimmed));
	char* real_folder = folder != NULL ? realpath(folder, NULL) : NULL;
	free(folder);
	char* out = real_folder != NULL ? malloc(strlen(real_folder) + strlen(name) + 2) : NULL;
	if (out != NULL)
		sprintf(out, "%s/%s", real_folder, name);
	free(real_folder);
	free(trimmed);
	return out;
}

bool cli_same_file(const char* a, const char* b)
{
	struct stat sa, sb;
	if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
		return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
	char* ca = canonical_path(a);
	char* cb = canonical_path(b);
	const bool same = ca != NULL && cb != NULL && strcmp(ca, cb) == 0;
	free(ca);
	free(cb);
	return same;
}

// Whether the file at path starts with `header`.
static bool starts_with(const char* path, const char* header)
{
	const size_t length = strlen(header);
	char start[128] = {0};
	if (length > sizeof start)
		return false;
	FILE* f = fopen(path, "rb");
	if (f == NULL)
		return false;
	const size_t got = fread(start, 1, length, f);
	fclose(f);
	return got == length && memcmp(start, header, length) == 0;
}

long cli_remove_series_tail(const char* prefix, int digits, long first, const char* extension,
                            const char* header)
{
	const size_t size = strlen(prefix) + strlen(extension) + 32;
	char* path = malloc(size);
	long removed = 0;
	for (long k = first; path != NULL; k++) {
		snprintf(path, size, "%s%0*ld%s", prefix, digits, k, extension);
		struct stat st;
		if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode) || !starts_with(path, header) || unlink(path) != 0)
			break;
		removed++;
	}
	free(path);
	return removed;
}

bool cli_inside(const char* path, const char* folder)
{
	char* place = canonical_path(path);
	char* real = realpath(folder, NULL);
	const size_t length = real != NULL ? strlen(real) : 0;
	const bool inside = place != NULL && real != NULL && strncmp(place, real, length) == 0 &&
	                    (place[length] == '/' || real[length - 1] == '/');
	free(place);
	free(real);
	return inside;
}

int cli_check_output_place(const char* command, const char* option, const char* path, bool folder)
{
	if (path == NULL || strcmp(path, "-") == 0)
		return 0;
	char* place = canonical_path(path);
	struct stat st;
	const bool exists = stat(path, &st) == 0;
	// Where the output is made: in the folder that holds its place (a new file or folder), or in
	// the file or folder there (a file may be rewritten in a folder that takes no new files).
	char* slash = place != NULL ? strrchr(place, '/') : NULL;
	if (slash != NULL)
		*(slash == place ? slash + 1 : slash) = '\0';
	const bool writable = place != NULL && (folder && exists ? access(path, W_OK | X_OK) == 0
	                                        : exists         ? access(path, W_OK) == 0
	                                                         : access(place, W_OK | X_OK) == 0);
	// The place of a new file or folder under a file ("notes.txt/out"): realpath takes the file for
	// its folder, and access would report it as a permission (or not at all, for an executable).
	struct stat holder;
	const bool under_file = place != NULL && !exists && stat(place, &holder) == 0 && !S_ISDIR(holder.st_mode);
	const char* wrong = place == NULL ? "the folder it would go in does not exist"
	                    : under_file  ? "the folder it would go in is a file"
	                    : exists && folder && !S_ISDIR(st.st_mode) ? "a file of that name exists"
	                    : exists && !folder && S_ISDIR(st.st_mode) ? "it is a folder"
	                    : !writable                                ? "permission denied"
	                                                               : NULL;
	free(place);
	if (wrong == NULL)
		return 0;
	cli_shown shown = {0};
	fprintf(stderr, "springmass %s: %s %s: cannot write there: %s\n", command, option,
	        cli_shown_path(&shown, path), wrong);
	cli_shown_free(&shown);
	return 1;
}

int cli_check_outputs_apart(const char* command, const char* option_a, const char* a, const char* option_b,
                            const char* b)
{
	if (a == NULL || b == NULL || !cli_same_file(a, b))
		return 0;
	cli_shown shown = {0};
	fprintf(
	    stderr,
	    "springmass %s: %s %s and %s %s are one file, which only the last would hold; give each its own\n",
	    command, option_a, cli_shown_path(&shown, a), option_b, cli_shown_path(&shown, b));
	cli_shown_free(&shown);
	return 2;
}

void cli_cannot_write(const char* command, const char* path)
{
	if (errno == EPIPE && cli_pipe_signal_waiting())
		return;  // the reader has gone, and the signal held back ends the command quietly
	const char* reason = errno != 0 ? strerror(errno) : "write error";
	cli_shown shown = {0};
	fprintf(stderr, "springmass %s: cannot write %s: %s\n", command, cli_shown_path(&shown, path), reason);
	cli_shown_free(&shown);
}

int cli_close(const char* command, const char* path, FILE* f)
{
	// A failed write leaves data in the buffer, so fclose fails again and sets errno afresh. A
	// write larger than the buffer (a saved model of 200 KB) goes past it and leaves nothing for
	// fclose to fail on: the reason is then that of the failed write, whose errno is still there.
	const int failed = ferror(f);
	const int earlier = errno;
	errno = 0;
	if (fclose(f) != 0 || failed) {
		if (errno == 0)
			errno = earlier;
		cli_cannot_write(command, path);
		return -1;
	}
	return 0;
}

int cli_model_argument(const char* command, const char* arg, const char** model)
{
	if (arg[0] == '-' && arg[1] != '\0') {
		cli_shown shown = {0};
		fprintf(stderr, "springmass %s: unknown option or missing value: %s\n\n", command,
		        cli_shown_text(&shown, arg));
		cli_shown_free(&shown);
		return 2;
	}
	if (*model != NULL) {
		cli_shown shown = {0};
		fprintf(stderr, "springmass %s: one model file at a time ('%s' and '%s' given)\n\n", command,
		        cli_shown_path(&shown, *model), cli_shown_path(&shown, arg));
		cli_shown_free(&shown);
		return 2;
	}
	*model = arg;
	return 0;
}

int cli_model_given(const char* command, const char* model)
{
	if (model != NULL)
		return 0;
	fprintf(stderr, "springmass %s: no model file given\n\n", command);
	return 2;
}

int32_t cli_total_load(const sm_model* model, double total[3])
{
	int32_t loaded = 0;
	total[0] = total[1] = total[2] = 0.0;
	for (int32_t i = 0; i < sm_model_particle_count(model); i++) {
		sm_particle_def pd;
		sm_model_get_particle(model, i, &pd);
		loaded += pd.load[0] != 0.0 || pd.load[1] != 0.0 || pd.load[2] != 0.0;
		for (int c = 0; c < 3; c++)
			total[c] += pd.load[c];
	}
	return loaded;
}

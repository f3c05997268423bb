// The input signals of `springmass run --input` (see cli_inputs.h).
#define _POSIX_C_SOURCE 200809L

#include "cli_inputs.h"

#include "cli_csv.h"
#include "cli_shown.h"
#include "text_file.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// A port's inputs in the file: quantity q (0 position, 1 velocity, 2 force), component c.
enum { QUANTITIES = 3, INPUTS_PER_PORT = 3 * QUANTITIES };
static const char* const suffixes[INPUTS_PER_PORT] = {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"};

struct cli_inputs {
	const sm_document* doc;
	int32_t port_count;
	cli_csv csv;
	int32_t* column;  // per port and input (INPUTS_PER_PORT each): its column in the file, or -1
	int64_t* turn;    // per row k: the first row at or after it where the inputs' course changes
	char why[256];    // a refused column's reason, while reading
};

// A column of the file: "PORT.SUFFIX", an input of a force or motion port.
static const char* name_column(void* context, const char* name, int32_t* id, cli_csv_values* values)
{
	cli_inputs* in = context;
	const char* dot = strrchr(name, '.');
	int32_t port = -1;
	if (dot != NULL) {
		char* port_name = strdup(name);
		if (port_name == NULL)
			return "cannot be read: out of memory";
		port_name[dot - name] = '\0';
		port = sm_document_port_index(in->doc, port_name);
		free(port_name);
	}
	int q = -1;
	for (int k = 0; dot != NULL && k < INPUTS_PER_PORT; k++)
		if (strcmp(dot + 1, suffixes[k]) == 0)
			q = k;
	if (port < 0 || q < 0)
		return "is no port's input: force port P takes P.fx, P.fy, P.fz, motion port P takes P.x .. P.vz";
	const sm_port p = sm_document_port(in->doc, port);
	if (p.kind == SM_PORT_PROBE)
		return "is a probe's: a probe takes no input";
	if ((p.kind == SM_PORT_FORCE) != (q >= 6)) {
		snprintf(in->why, sizeof in->why, "is an output: %s port %s takes %s",
		         p.kind == SM_PORT_FORCE ? "force" : "motion", p.name,
		         p.kind == SM_PORT_FORCE ? "a force (.fx .fy .fz)" : "a position and velocity (.x .. .vz)");
		return in->why;
	}
	*id = INPUTS_PER_PORT * port + q;
	*values = CLI_CSV_REAL;
	return NULL;
}

// A malloc'd message from a format, or NULL when memory runs out.
static char* message(const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static char* message(const char* format, ...)
{
	char text[512];
	va_list args;
	va_start(args, format);
	vsnprintf(text, sizeof text, format, args);
	va_end(args);
	return strdup(text);
}

// Whether the inputs go on through row k as they came to it: every signal at the same slope on
// both sides (held before the first row and after the last: slope 0 there), no jump (a repeated
// time), and no particle component given both a position and a velocity (the positions given
// would set it back at every row from where the velocities have taken it). CVODE then need not
// stop at the row: a table sampled finely where its signals are constant or linear costs no
// more steps than its changes do.
static bool course_kept(const cli_inputs* in, int64_t k)
{
	const int64_t n = in->csv.columns, rows = in->csv.rows;
	const double* v = in->csv.values;
	if ((k > 0 && !(v[k * n] > v[(k - 1) * n])) || (k + 1 < rows && !(v[(k + 1) * n] > v[k * n])))
		return false;
	for (int64_t c = 1; c < n; c++) {
		const double before = k > 0 ? (v[k * n + c] - v[(k - 1) * n + c]) / (v[k * n] - v[(k - 1) * n]) : 0.0;
		const double after =
		    k + 1 < rows ? (v[(k + 1) * n + c] - v[k * n + c]) / (v[(k + 1) * n] - v[k * n]) : 0.0;
		if (before != after)
			return false;
	}
	return true;
}

// The rows where the inputs' course changes (course_kept), each row's next one at or after it
// (rows when none is left). False when memory runs out.
static bool find_turns(cli_inputs* in)
{
	const int64_t rows = in->csv.rows;
	in->turn = malloc(((size_t)rows + 1) * sizeof *in->turn);
	if (in->turn == NULL)
		return false;
	bool both = false;  // a component given as a position and as a velocity
	for (int32_t p = 0; p < in->port_count; p++)
		for (int c = 0; c < 3; c++)
			both = both ||
			       (in->column[INPUTS_PER_PORT * p + c] >= 0 && in->column[INPUTS_PER_PORT * p + 3 + c] >= 0);
	in->turn[rows] = rows;
	for (int64_t k = rows - 1; k >= 0; k--)
		in->turn[k] = !both && course_kept(in, k) ? in->turn[k + 1] : k;
	return true;
}

// The column (from 1, in bytes, as cli_csv_read counts them) where field `field` (from 0) of line
// `line` (from 1) of a text cli_csv_read took starts: its rows are a line each, their fields
// unquoted, so the line's commas part them.
static size_t field_column(const char* text, size_t length, int64_t line, int64_t field)
{
	size_t at = 0;
	for (int64_t l = 1; l < line; l++)
		at = (size_t)((const char*)memchr(text + at, '\n', length - at) - text) + 1;
	const size_t start = at;
	for (int64_t c = 0; c < field; c++)
		at = (size_t)((const char*)memchr(text + at, ',', length - at) - text) + 1;
	return at - start + 1;
}

cli_inputs* cli_inputs_parse(const char* text, size_t length, const sm_document* doc, char** problem)
{
	*problem = NULL;
	cli_inputs* in = calloc(1, sizeof *in);
	const int32_t ports = sm_document_port_count(doc);
	int32_t* column = malloc(((size_t)ports * INPUTS_PER_PORT + 1) * sizeof *column);
	if (in == NULL || column == NULL) {
		free(in);
		free(column);
		return NULL;
	}
	in->doc = doc;
	in->port_count = ports;
	in->column = column;
	const cli_csv_form form = {"an input file", name_column, in, ports * INPUTS_PER_PORT, true};
	bool out_of_memory = false;
	*problem = cli_csv_read(text, length, &form, &in->csv, &out_of_memory);
	if (*problem != NULL || out_of_memory) {
		cli_inputs_destroy(in);
		return NULL;
	}
	for (int32_t k = 0; k < ports * INPUTS_PER_PORT; k++)
		column[k] = -1;
	for (int32_t c = 1; c < in->csv.columns; c++)
		column[in->csv.id[c]] = c;
	// Each signal's slope from one row to the next (rows one per line after the header), checked
	// before the run rather than when it gets there.
	const int64_t n = in->csv.columns;
	const double* v = in->csv.values;
	for (int64_t k = 1; k < in->csv.rows; k++)
		for (int64_t c = 1; c < n && v[k * n] > v[(k - 1) * n]; c++)
			if (!isfinite((v[k * n + c] - v[(k - 1) * n + c]) / (v[k * n] - v[(k - 1) * n]))) {
				const int32_t id = in->csv.id[c];
				*problem =
				    message("%lld:%zu: %s.%s: the slope from the row before is beyond a double (rows "
					        "too close in time for their values)",
					        (long long)k + 2, field_column(text, length, k + 2, c),
					        sm_document_port(doc, id / INPUTS_PER_PORT).name, suffixes[id % INPUTS_PER_PORT]);
				cli_inputs_destroy(in);
				return NULL;
			}
	if (!find_turns(in)) {
		cli_inputs_destroy(in);
		return NULL;
	}
	return in;
}

// Standard input to its end, at most TEXT_FILE_MAX_BYTES as a file; NULL with *problem set if it
// cannot. The buffer grows to one byte past the limit (and one for the final NUL): a text of the
// limit leaves it one short of full when the end is seen, a byte more fills it.
static char* read_standard_input(size_t* length, const char** problem)
{
	const size_t most = (size_t)TEXT_FILE_MAX_BYTES;
	size_t size = 0, capacity = 0;
	char* text = NULL;
	for (;;) {
		if (size == capacity) {
			char* grown = NULL;
			if (capacity <= most) {
				capacity = capacity ? 2 * capacity : 65536;
				if (capacity > most + 1)
					capacity = most + 1;
				grown = realloc(text, capacity + 1);
			}
			if (grown == NULL) {
				*problem = size <= most ? "out of memory" : "larger than 1 GiB";
				free(text);
				return NULL;
			}
			text = grown;
		}
		const size_t got = fread(text + size, 1, capacity - size, stdin);
		size += got;
		if (got == 0)
			break;
	}
	if (ferror(stdin)) {
		*problem = strerror(errno);
		free(text);
		return NULL;
	}
	text[size] = '\0';
	*length = size;
	return text;
}

cli_inputs* cli_inputs_read(const char* path, const sm_document* doc)
{
	const char* unreadable = NULL;
	size_t length = 0;
	const bool standard = strcmp(path, "-") == 0;
	char* text =
	    standard ? read_standard_input(&length, &unreadable) : text_file_read(path, &length, &unreadable);
	cli_shown shown = {0};
	if (text == NULL) {
		fprintf(stderr, "springmass run: cannot read the input signals %s: %s\n",
		        standard ? "from standard input" : cli_shown_path(&shown, path), unreadable);
		cli_shown_free(&shown);
		return NULL;
	}
	char* problem = NULL;
	cli_inputs* in = cli_inputs_parse(text, length, doc, &problem);
	free(text);
	if (in == NULL)
		fprintf(stderr, "springmass run: --input %s:%s\n", cli_shown_path(&shown, path),
		        problem != NULL ? problem : " out of memory");
	cli_shown_free(&shown);
	free(problem);
	return in;
}

// Whether the signals name any input of port p.
static bool named(const cli_inputs* in, int32_t p)
{
	for (int k = 0; k < INPUTS_PER_PORT; k++)
		if (in->column[INPUTS_PER_PORT * p + k] >= 0)
			return true;
	return false;
}

sm_status cli_inputs_drive(const cli_inputs* in, sm_model* model)
{
	for (int32_t p = 0; p < in->port_count; p++) {
		const sm_port port = sm_document_port(in->doc, p);
		if (port.kind != SM_PORT_MOTION || !named(in, p))
			continue;
		sm_particle_def def;
		sm_status st = sm_model_get_particle(model, port.particle, &def);
		if (st != SM_OK)
			return st;
		if (def.motion == SM_PARTICLE_FIXED)
			def.velocity[0] = def.velocity[1] = def.velocity[2] = 0.0;
		def.motion = SM_PARTICLE_DRIVEN;
		if ((st = sm_model_set_particle(model, port.particle, &def)) != SM_OK)
			return st;
	}
	return SM_OK;
}

// The row of the signals in force at t: the last one at or before t, or -1 before the first.
static int64_t row_at(const cli_inputs* in, double t)
{
	int64_t lo = 0, hi = in->csv.rows;  // the answer + 1 lies in [lo, hi]
	while (lo < hi) {
		const int64_t mid = lo + (hi - lo) / 2;
		if (in->csv.values[mid * in->csv.columns] <= t)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo - 1;
}

// The time of the first row after t [s] where the inputs change their course, or INFINITY.
static double next_change(const cli_inputs* in, double t)
{
	const int64_t k = in->turn[row_at(in, t) + 1];
	return k < in->csv.rows ? in->csv.values[k * in->csv.columns] : INFINITY;
}

// Signal `column` at t and its slope until the next row (0 before the first row and after the
// last). Between rows k and k + 1: v_k + slope (t - t_k), slope = (v_k+1 - v_k) / (t_k+1 - t_k).
static void signal_at(const cli_inputs* in, int32_t column, double t, double* value, double* slope)
{
	const int64_t k = row_at(in, t), n = in->csv.columns;
	const double* v = in->csv.values;
	*slope = 0.0;
	if (k < 0) {
		*value = v[column];
		return;
	}
	*value = v[k * n + column];
	if (k + 1 < in->csv.rows) {
		*slope = (v[(k + 1) * n + column] - *value) / (v[(k + 1) * n] - v[k * n]);
		*value += *slope * (t - v[k * n]);
	}
}

sm_status cli_inputs_apply(const cli_inputs* in, sm_simulation* sim, char* why, size_t size)
{
	const double t = sm_simulation_time(sim);
	why[0] = '\0';
	for (int32_t p = 0; p < in->port_count; p++) {
		const sm_port port = sm_document_port(in->doc, p);
		if (port.kind == SM_PORT_PROBE || !named(in, p))
			continue;
		const int32_t* column = in->column + INPUTS_PER_PORT * p;
		const size_t i = 3 * (size_t)port.particle;
		double value[INPUTS_PER_PORT], slope[INPUTS_PER_PORT];
		for (int k = 0; k < INPUTS_PER_PORT; k++) {
			value[k] = slope[k] = 0.0;
			if (column[k] >= 0)
				signal_at(in, column[k], t, &value[k], &slope[k]);
			if (!isfinite(value[k]) || !isfinite(slope[k])) {
				snprintf(why, size, "%s.%s at t = %.17g s: its %s to the next row is beyond a double",
				         port.name, suffixes[k], t, isfinite(slope[k]) ? "value" : "slope");
				return SM_ERROR_NOT_FINITE;
			}
		}
		sm_status st;
		if (port.kind == SM_PORT_FORCE) {
			st = sm_simulation_set_external_force_ramp(sim, port.particle, value + 6, slope + 6);
		} else {
			// Per component: positions and velocities given; positions (at their slope); velocities
			// (accelerating at theirs) from where the motion is; or the motion as it is.
			double x[3], v[3], a[3];
			for (int c = 0; c < 3; c++) {
				const bool position = column[c] >= 0, velocity = column[3 + c] >= 0;
				x[c] = position ? value[c] : sm_simulation_positions(sim)[i + c];
				v[c] = velocity ? value[3 + c] : position ? slope[c] : sm_simulation_velocities(sim)[i + c];
				a[c] = velocity ? slope[3 + c] : 0.0;
			}
			st = sm_simulation_set_driven_accelerating(sim, port.particle, x, v, a);
		}
		if (st != SM_OK) {
			snprintf(why, size, "port %s at t = %.17g s: %s", port.name, t, sm_simulation_last_error(sim));
			return st;
		}
	}
	return SM_OK;
}

sm_status cli_inputs_advance(const cli_inputs* in, sm_simulation* sim, double t, double t_stop, char* why,
                             size_t size)
{
	why[0] = '\0';
	if (in == NULL)
		return sm_simulation_advance_interpolated(sim, t, t_stop);
	for (double change = next_change(in, sm_simulation_time(sim)); change <= t;
	     change = next_change(in, change)) {
		sm_status st = sm_simulation_advance_interpolated(sim, change, change);
		if (st == SM_OK)
			st = cli_inputs_apply(in, sim, why, size);
		if (st != SM_OK)
			return st;
	}
	return sm_simulation_advance_interpolated(sim, t, fmax(t, fmin(t_stop, next_change(in, t))));
}

void cli_inputs_destroy(cli_inputs* in)
{
	if (in == NULL)
		return;
	cli_csv_free(&in->csv);
	free(in->column);
	free(in->turn);
	free(in);
}

// The progress line of a long command (cli_progress.h).
#define _POSIX_C_SOURCE 200809L

#include "cli_progress.h"

#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

double cli_wall_clock(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void cli_progress_start(cli_progress* p)
{
	p->terminal = isatty(fileno(stderr));
	p->period = p->terminal ? 0.5 : 5.0;
	p->start = p->last = cli_wall_clock();
	p->shown = false;
	p->width = 0;
}

bool cli_progress_due(const cli_progress* p, bool last_one)
{
	const double now = cli_wall_clock();
	return p->start != 0.0 && now - p->start > 1.0 && (now - p->last > p->period || last_one);
}

void cli_progress_show(cli_progress* p, const char* line)
{
	const int width = (int)strlen(line);
	if (p->terminal)
		fprintf(stderr, "\r%s%*s", line, p->width > width ? p->width - width : 0, "");
	else
		fprintf(stderr, "%s\n", line);
	p->width = width;
	p->last = cli_wall_clock();
	p->shown = true;
}

void cli_progress_end(const cli_progress* p)
{
	if (p->shown && p->terminal)
		fprintf(stderr, "\n");
}

// The progress of a statics solve: the line, what it starts with and the iteration limit.
typedef struct statics_progress {
	cli_progress line;
	const char* label;
	int32_t max_iterations;
} statics_progress;

static void show_statics_progress(statics_progress* p, int32_t iterations, double residual, bool last)
{
	if (!cli_progress_due(&p->line, last))
		return;
	char line[160];
	snprintf(line, sizeof line, "%s: iteration %d of at most %d, largest force %.3g N, %.1f s", p->label,
	         (int)iterations, (int)p->max_iterations, residual, cli_wall_clock() - p->line.start);
	cli_progress_show(&p->line, line);
}

static bool on_statics_iteration(void* context, int32_t iterations, double residual)
{
	show_statics_progress(context, iterations, residual, false);
	return true;
}

sm_status cli_statics_solve(const char* label, bool quiet, const sm_model* model, const sm_statics_def* def,
                            double* x, double* reactions, sm_statics_result* res, sm_error* err)
{
	// The callback goes into a copy: the caller's definition never points at this frame.
	sm_statics_def shown = *def;
	statics_progress progress = {.label = label, .max_iterations = def->max_iterations};
	if (!quiet) {
		shown.on_iteration = on_statics_iteration;
		shown.on_iteration_context = &progress;
	}
	cli_progress_start(&progress.line);
	const sm_status st = sm_statics_solve(model, &shown, x, reactions, res, err);
	if (!quiet)
		show_statics_progress(&progress, res->iterations, res->residual, true);
	cli_progress_end(&progress.line);
	return st;
}

// The progress of the Lanczos iteration of sm_modes_compute: the line and what it last heard.
typedef struct modes_progress {
	cli_progress line;
	const char* label;
	int64_t steps;
	int32_t converged, sought;
} modes_progress;

static void show_modes_progress(modes_progress* p, bool last)
{
	if (p->steps == 0 || !cli_progress_due(&p->line, last))
		return;
	char line[160];
	snprintf(line, sizeof line, "%s: Lanczos step %lld, %d of %d modes converged in this run, %.1f s",
	         p->label, (long long)p->steps, (int)p->converged, (int)p->sought,
	         cli_wall_clock() - p->line.start);
	cli_progress_show(&p->line, line);
}

static bool on_lanczos_cycle(void* context, int64_t steps, int32_t converged, int32_t sought)
{
	modes_progress* p = context;
	p->steps = steps;
	p->converged = converged;
	p->sought = sought;
	show_modes_progress(p, false);
	return true;
}

sm_status cli_modes_compute(const char* label, const sm_model* model, const sm_modes_def* def,
                            sm_modes* modes, sm_error* err)
{
	sm_modes_def shown = *def;  // as in cli_statics_solve
	modes_progress progress = {.label = label};
	shown.on_iteration = on_lanczos_cycle;
	shown.on_iteration_context = &progress;
	cli_progress_start(&progress.line);
	const sm_status st = sm_modes_compute(model, &shown, modes, err);
	show_modes_progress(&progress, true);
	cli_progress_end(&progress.line);
	return st;
}

// The progress line of a long command on stderr, from one second into the work on: on a terminal
// it rewrites itself every half second; in a log it is one line every five seconds. A command that
// shows one ends it with cli_progress_end before writing anything else to stderr.
#pragma once

#include "springmass/analysis.h"

#include <stdbool.h>

typedef struct cli_progress {
	double start;   ///< wall-clock time of the start [s]; 0 until cli_progress_start
	double last;    ///< when the line was last shown [s]
	double period;  ///< between two lines [s]
	bool terminal;  ///< stderr is a terminal: the line rewrites itself
	bool shown;     ///< a line has been shown
	int width;      ///< characters of the line last shown on a terminal, which the next one covers
} cli_progress;

/// Monotonic wall-clock time [s].
double cli_wall_clock(void);

/// Starts the clock; the period follows from whether stderr is a terminal.
void cli_progress_start(cli_progress* p);

/// Whether a line is due now: more than a second since the start and a period since the last line,
/// or, with `last_one`, the work's last line once any other would have been shown.
bool cli_progress_due(const cli_progress* p, bool last_one);

/// Shows `line` (without a newline) and notes when.
void cli_progress_show(cli_progress* p, const char* line);

/// Ends a line that rewrites itself, before other output.
void cli_progress_end(const cli_progress* p);

/// sm_statics_solve with the progress line of a static equilibrium (springmass statics, modes
/// --at-equilibrium), unless `quiet`: a line after Newton iterations (through on_iteration, set in
/// a copy of `def`) and the last one after the solve, each starting with `label`.
sm_status cli_statics_solve(const char* label, bool quiet, const sm_model* model, const sm_statics_def* def,
                            double* x, double* reactions, sm_statics_result* res, sm_error* err);

/// sm_modes_compute with a progress line of its Lanczos iteration (sparse path), each line
/// starting with `label`, and the last one after it (through on_iteration, set in a copy of `def`).
sm_status cli_modes_compute(const char* label, const sm_model* model, const sm_modes_def* def,
                            sm_modes* modes, sm_error* err);

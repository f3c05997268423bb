// Outputs of a command that are written all or none: each file is written beside its place under
// a temporary name, and every one is moved to its place once all are written; a failure on the way
// removes the temporaries and leaves every place as it was (a file there before is replaced only
// then, whole, and keeps its permissions; only a rename that fails after others, which a folder
// that took a new file does not refuse but on a fault of the file system, leaves those before it
// moved). A command killed while writing (Ctrl-C) leaves its temporaries, hidden files named
// .springmass-<pid>-<k>.partial, and every place as it was; one whose output is a pipe whose
// reader has gone (-o /dev/stdout) removes them first: SIGPIPE is held back while outputs are open.
#pragma once

#include <stdbool.h>
#include <stdio.h>

typedef struct cli_output {
	char* temporary;  ///< the file written, beside path; NULL where path is written directly
	char* path;       ///< the output's place
} cli_output;

typedef struct cli_outputs {
	const char* command;  ///< the subcommand, for messages
	int count, capacity;
	cli_output* items;
	bool pipe_held;  ///< SIGPIPE held back since the first output was opened (cli_hold_pipe_signal)
} cli_outputs;

/// Opens a new output at `path` for writing, to be closed with cli_close (which reports write
/// errors under `path`). A place that holds something other than a regular file (a link, a device
/// such as /dev/null), and a file in a folder where no temporary can be made, is opened directly,
/// as fopen would. Prints the error and returns NULL on failure.
FILE* cli_outputs_open(cli_outputs* outputs, const char* path);

/// Moves every output to its place, in the order opened. Returns 0, or prints why and returns -1
/// (the outputs not moved yet are removed).
int cli_outputs_commit(cli_outputs* outputs);

/// Removes the temporaries of the outputs not committed, frees the list and lets a SIGPIPE held
/// back take effect; call it always, after a commit too.
void cli_outputs_discard(cli_outputs* outputs);

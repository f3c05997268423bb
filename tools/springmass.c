// springmass: the command-line tool. Dispatches to one subcommand per file.
#define _GNU_SOURCE  // RTLD_DEFAULT

#include "cli_shown.h"
#include "cli_signals.h"
#include "commands.h"

#include "springmass/base.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <gsl/gsl_errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct command {
	const char* name;
	int (*run)(int argc, char** argv);
	const char* summary;
} command;

static const command commands[] = {
    {"check", sm_cmd_check, "validate a model file and print a summary"},
    {"run", sm_cmd_run, "simulate a model (CSV and VTK output)"},
    {"statics", sm_cmd_statics, "find the static equilibrium"},
    {"modes", sm_cmd_modes, "natural frequencies and mode shapes"},
    {"fmu", sm_cmd_fmu, "package a model file as an FMI 2.0 Co-Simulation FMU"},
};

static void usage(FILE* out)
{
	fprintf(out, "usage: springmass <command> [options]\n\ncommands:\n");
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) {
		fprintf(out, "  %-9s %s\n", commands[i].name, commands[i].summary);
	}
	fprintf(out, "\n`springmass <command> --help` (or `springmass help <command>`) explains a command; "
	             "`springmass --version` prints the version.\n");
}

// CHOLMOD's supernodal factorisations call BLAS, and Debian's OpenBLAS starts a thread per core
// when it is loaded, whose waiting spins. The tool owns its process, so unless
// OPENBLAS_NUM_THREADS says otherwise it runs BLAS on one thread. Measured on a 2-core machine
// with the other core busy: `springmass statics models/cloth.json` 1.47 s with two threads and
// 0.49 s with one; `modes` of a 64 x 64 membrane (lowest 10) 5.3 - 6.1 s against 2.4 - 3.0 s.
// The library itself leaves this process-wide setting to the program that embeds it. Found at
// run time, so that any other BLAS works too.
static void single_threaded_blas(void)
{
	if (getenv("OPENBLAS_NUM_THREADS") != NULL)
		return;
	void (*set_threads)(int);
	*(void**)&set_threads = dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
	if (set_threads != NULL)
		set_threads(1);
}

// Standard input, output and error are open, if only on /dev/null: a stream the caller closed
// (`2>&-`) would otherwise be the descriptor the next file opened gets, and the reports written
// to it would land in the CSV or the series' index. A closed standard output is opened for
// reading only and a closed standard input for writing only, so that what the command writes to
// the one or reads from the other fails (EBADF) as on the closed stream: a report or a CSV written
// to a closed standard output is an output that cannot be written, not one silently thrown away.
// Diagnostics to a closed standard error go nowhere, without failing the command.
static void open_standard_streams(void)
{
	for (int fd = 0; fd <= 2; fd++)
		if (fcntl(fd, F_GETFD) == -1 && errno == EBADF) {
			// The lowest free descriptor, fd itself (without /dev/null, as in a bare chroot, none).
			const int opened = open("/dev/null", fd == 1 ? O_RDONLY : O_WRONLY);
			if (opened >= 0 && opened != fd)
				close(opened);
		}
}

// A report that could not be written to standard output (a full disk) fails the command, as in
// any Unix tool; a command that failed has already said why. The cause is the flush's, or else
// that of the write that failed before it, whose errno is still there: a report longer than
// stdio's buffer (a help text of 4 KB) is written past the buffer and fails there, leaving nothing
// for the flush to fail on.
static int finish(int status)
{
	const int earlier = errno;
	errno = 0;
	if ((fflush(stdout) != 0 || ferror(stdout)) && status == 0) {
		const int cause = errno != 0 ? errno : earlier;
		fprintf(stderr, "springmass: cannot write standard output: %s\n",
		        cause != 0 ? strerror(cause) : "write error");
		return 1;
	}
	return status;
}

int main(int argc, char** argv)
{
	open_standard_streams();
	cli_settle_blocked_pipe_signal();
	single_threaded_blas();
	// Failures inside GSL come back as status codes, reported like any other error, instead of
	// GSL's default abort (include/springmass/analysis.h).
	gsl_set_error_handler_off();
	if (argc < 2) {
		usage(stderr);
		return 2;
	}
	if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 ||
	    (strcmp(argv[1], "help") == 0 && argc == 2)) {
		usage(stdout);
		return finish(0);
	}
	// `springmass help COMMAND` is `springmass COMMAND --help`.
	char* help_args[] = {argc > 2 ? argv[2] : NULL, "--help", NULL};
	const bool help = strcmp(argv[1], "help") == 0;
	if (help && argc > 3) {
		fprintf(stderr, "springmass help: one command at most\n\n");
		usage(stderr);
		return 2;
	}
	if (strcmp(argv[1], "--version") == 0) {
		printf("springmass %s\n", sm_version());
		return finish(0);
	}
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) {
		if (help && strcmp(argv[2], commands[i].name) == 0)
			return finish(commands[i].run(2, help_args));
		if (!help && strcmp(argv[1], commands[i].name) == 0)
			return finish(commands[i].run(argc - 1, argv + 1));
	}
	cli_shown shown = {0};
	fprintf(stderr, "springmass: unknown command '%s'\n\n", cli_shown_text(&shown, help ? argv[2] : argv[1]));
	cli_shown_free(&shown);
	usage(stderr);
	return 2;
}

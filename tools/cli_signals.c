// Stopping a command from outside (cli_signals.h).
#define _POSIX_C_SOURCE 200809L

#include "cli_signals.h"

#include <stdio.h>
#include <string.h>

volatile sig_atomic_t cli_stop_signal;

static void note_signal(int signal)
{
	cli_stop_signal = signal;
}

void cli_catch_stop_signals(bool pipe)
{
	struct sigaction action;
	memset(&action, 0, sizeof action);
	action.sa_handler = note_signal;
	action.sa_flags = SA_RESTART;
	sigemptyset(&action.sa_mask);
	sigaction(SIGINT, &action, NULL);
	sigaction(SIGTERM, &action, NULL);
	sigaction(SIGHUP, &action, NULL);
	if (pipe)
		sigaction(SIGPIPE, &action, NULL);
}

void cli_end_by_stop_signal(void)
{
	if (cli_stop_signal == 0)
		return;
	fflush(stdout);
	signal(cli_stop_signal, SIG_DFL);
	raise(cli_stop_signal);
}

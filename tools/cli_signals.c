// Stopping a command from outside (cli_signals.h).
#define _POSIX_C_SOURCE 200809L

#include "cli_signals.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

volatile sig_atomic_t cli_stop_signal;

static void note_signal(int signal)
{
	cli_stop_signal = signal;
}

bool cli_signal_ignored(int signal)
{
	struct sigaction current;
	return sigaction(signal, NULL, &current) == 0 && current.sa_handler == SIG_IGN;
}

void cli_settle_blocked_pipe_signal(void)
{
	sigset_t mask;
	if (pthread_sigmask(SIG_BLOCK, NULL, &mask) != 0 || !sigismember(&mask, SIGPIPE))
		return;
	struct sigaction ignore;
	memset(&ignore, 0, sizeof ignore);
	ignore.sa_handler = SIG_IGN;
	sigemptyset(&ignore.sa_mask);
	sigaction(SIGPIPE, &ignore, NULL);
}

// Catches `signal` unless the process was started with it ignored.
static void catch_signal(int signal, const struct sigaction* action)
{
	if (!cli_signal_ignored(signal))
		sigaction(signal, action, NULL);
}

void cli_catch_stop_signals(bool pipe)
{
	struct sigaction action;
	memset(&action, 0, sizeof action);
	action.sa_handler = note_signal;
	action.sa_flags = SA_RESTART;
	sigemptyset(&action.sa_mask);
	catch_signal(SIGINT, &action);
	catch_signal(SIGTERM, &action);
	catch_signal(SIGHUP, &action);
	if (pipe)
		catch_signal(SIGPIPE, &action);
}

void cli_end_by_stop_signal(void)
{
	if (cli_stop_signal == 0)
		return;
	fflush(stdout);
	signal(cli_stop_signal, SIG_DFL);
	raise(cli_stop_signal);
}

bool cli_hold_pipe_signal(void)
{
	sigset_t pipe, before;
	sigemptyset(&pipe);
	sigaddset(&pipe, SIGPIPE);
	return pthread_sigmask(SIG_BLOCK, &pipe, &before) == 0 && !sigismember(&before, SIGPIPE);
}

void cli_release_pipe_signal(bool held)
{
	if (!held)
		return;
	sigset_t pipe;
	sigemptyset(&pipe);
	sigaddset(&pipe, SIGPIPE);
	pthread_sigmask(SIG_UNBLOCK, &pipe, NULL);
}

bool cli_pipe_signal_waiting(void)
{
	sigset_t waiting;
	return sigpending(&waiting) == 0 && sigismember(&waiting, SIGPIPE) && !cli_signal_ignored(SIGPIPE);
}

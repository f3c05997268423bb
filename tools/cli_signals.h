// A command stopped from outside (Ctrl-C, a kill, the terminal closed): the handler only notes the
// signal; the command stops at its next check, leaves its files whole (or removes what it had not
// finished), and ends by the same signal, so that its exit status is the one it would have had
// without a handler (128 + the signal's number in a shell).
#pragma once

#include <signal.h>
#include <stdbool.h>

/// The signal that asked the command to stop, 0 until one came. A command may set it itself (run
/// sets SIGPIPE when the reader of its output has gone).
extern volatile sig_atomic_t cli_stop_signal;

/// From now on SIGINT, SIGTERM and SIGHUP (and SIGPIPE if `pipe`: a write to a pipe whose reader
/// has gone then fails with EPIPE) are noted in cli_stop_signal instead of ending the process; a
/// write or a wait they interrupt goes on (SA_RESTART): no row is cut, waiting for a child goes on.
/// A signal the process was started with ignored stays ignored, as the one who started it asked
/// (SIGHUP under nohup, SIGINT in a shell script's background job; SIGPIPE ignored makes a write
/// to a pipe without a reader an error like any other).
void cli_catch_stop_signals(bool pipe);

/// Whether `signal` is ignored now (SIG_IGN).
bool cli_signal_ignored(int signal);

/// Takes a SIGPIPE blocked in the signal mask the tool was started with as ignored, which it
/// amounts to: the tool unblocks no signal it did not block itself, so such a signal never ends
/// it, and a write to a pipe whose reader has gone is then an output that cannot be written,
/// reported with its reason as with SIGPIPE ignored (not a failure without a word, the signal
/// waiting in vain to end the command). Called once, at the start (the disposition is the
/// process's, whatever threads a library has started).
void cli_settle_blocked_pipe_signal(void);

/// Ends the process by the signal noted, with its default action; returns if none was noted.
void cli_end_by_stop_signal(void);

/// Holds SIGPIPE back in the calling thread while a command has files to remove before it ends
/// (temporaries of its outputs, the FMU's staging folder): a write to a pipe whose reader has gone
/// fails with EPIPE instead of ending the process at once, and the signal waits. Returns whether it
/// was held here (false: it was blocked already), to be given to cli_release_pipe_signal.
bool cli_hold_pipe_signal(void);

/// Lets a SIGPIPE held back by cli_hold_pipe_signal (if `held`) take effect: a reader gone ends the
/// process now, as it would have at the write (unless SIGPIPE is ignored or caught).
void cli_release_pipe_signal(bool held);

/// Whether a SIGPIPE held back is waiting, the process to end by it once released (and it is not
/// ignored): a failed write to that pipe needs no message, the reader being gone.
bool cli_pipe_signal_waiting(void);

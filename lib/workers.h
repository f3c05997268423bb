// A team of threads that runs one job over a number of chunks: the caller's thread and the
// helpers take the chunks one at a time until none is left (a helper the processors have no
// time for leaves its share to the others), and sm_workers_run returns when every chunk is done.
// Which thread runs a chunk never changes what it computes, so a job whose chunks write disjoint
// data, and whose caller combines per-chunk sums in chunk order, gives the same bits with any
// number of threads.
//
// Helpers wait for work by spinning briefly (a job every few microseconds, as in the iterations
// of conjugate gradients, costs no wake-up) and then sleep on a condition variable. Each team
// belongs to one owner (a simulation's linear solver); nothing is shared between teams.
#ifndef SPRINGMASS_WORKERS_H
#define SPRINGMASS_WORKERS_H

#include <stdbool.h>

typedef struct sm_workers sm_workers;

typedef void (*sm_worker_job)(void* context, int chunk);

// A team of `threads` threads, the caller's included (threads - 1 helpers are started); NULL if
// threads < 2 or a thread or memory cannot be had (the caller then runs every chunk itself).
sm_workers* sm_workers_create(int threads);

// Runs job(context, c) for c = 0 .. chunks - 1 and returns when all are done; with a NULL team,
// or in a child process forked after the team started, on the caller's thread, in order. Every
// chunk runs in the caller's floating-point environment, and the exception flags the helpers'
// chunks raise are raised in the caller's thread before the return.
void sm_workers_run(sm_workers* workers, sm_worker_job job, void* context, int chunks);

// The processors this process may run on: its affinity mask (what taskset or a container's CPU
// limit leaves it), else those online; at least 1.
int sm_workers_processors(void);

// Stops and joins the helpers; accepts NULL.
void sm_workers_destroy(sm_workers* workers);

#endif

// A team of threads for the chunks of one job at a time (workers.h).
//
// Claiming. The threads take a job's chunks one at a time from a shared ticket, the caller as
// well as the helpers, so a helper that has not been scheduled yet (the processors busy with
// other work) holds nothing up: the caller takes the chunks it leaves. The ticket packs the job's
// generation (32 bits), its chunk count and the next chunk (16 bits each); a thread claims a
// chunk by a compare-and-swap that adds 1, which fails once the ticket belongs to another job.
// A claimed chunk keeps its job alive: the caller returns only when `done` reaches the count, so
// the job's fields stay as they were until every claimer has finished with them.
//
// Hand-off. The caller stores the job's fields and `done` = 0, then the new ticket (sequentially
// consistent, so a release): a claim that reads that ticket, or a later one of the same job,
// sees the fields. A helper about to sleep counts itself in `sleeping` and checks the ticket
// again under the lock, and the caller reads `sleeping` after storing the ticket: of the two
// sequentially consistent operations one sees the other, so either the helper sees the new
// ticket or the caller sees it sleeping and wakes it under the lock. Completion: each claimer
// adds 1 to `done` after its chunk (release), and the caller spins until it reads the count
// (acquire), which makes the chunks' writes visible to it.
//
// Floating-point environment. A thread starts with the environment of the thread that created
// it, and the caller's may change after that (its rounding mode, flushing of subnormals), or the
// caller may be another thread: the caller stores its environment with each job and the helpers
// take it before their chunks, so that a chunk gives the same bits on whichever thread runs it.
// The exception flags their chunks raise (a division by zero, an overflow) are gathered in
// `raised` and raised in the caller's thread when the job is done, as if it had run every chunk
// itself: a caller that tests the flags after a simulation call sees the same with any number of
// threads.
#define _GNU_SOURCE  // sched_getaffinity, CPU_COUNT

#include "workers.h"

#include <fenv.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

// Polls of the ticket before a helper sleeps: about 50 - 100 us on current x86-64 processors,
// longer than the gap between the jobs of one conjugate-gradient iteration, much shorter than
// that between two simulation calls. Every YIELD_EVERY polls a waiting thread (helper or caller)
// yields its processor, so that a thread it waits for gets to run when there are more threads
// than processors.
#define SPIN_LIMIT 20000
#define YIELD_EVERY 1024
#define MAX_CHUNKS 0xffff

typedef struct helper {
	struct sm_workers* team;
	pthread_t thread;
} helper;

struct sm_workers {
	int threads;  // the caller's included
	int started;  // helpers running
	helper* helpers;
	pthread_mutex_t lock;
	pthread_cond_t wake;
	atomic_uint_least64_t ticket;  // generation << 32 | chunks << 16 | next chunk
	atomic_int done;               // chunks of the current job finished
	atomic_int sleeping;
	atomic_bool stop;   // read by helpers that may lag a job behind
	atomic_int raised;  // floating-point exception flags raised by helpers in the current job
	sm_worker_job job;
	void* context;
	fenv_t environment;  // the caller's, for the job
	pid_t process;       // that started the helpers
};

static inline void relax(int polls)
{
	if (polls % YIELD_EVERY == YIELD_EVERY - 1) {
		sched_yield();
		return;
	}
#if defined(__x86_64__) || defined(__i386__)
	__builtin_ia32_pause();
#endif
}

static inline unsigned generation_of(uint_least64_t ticket)
{
	return (unsigned)(ticket >> 32);
}

// Runs chunks of the current job while there are any left to claim.
static void claim_chunks(struct sm_workers* w, bool helper)
{
	uint_least64_t t = atomic_load(&w->ticket);
	for (;;) {
		const unsigned next = (unsigned)(t & 0xffff), chunks = (unsigned)((t >> 16) & 0xffff);
		if (next >= chunks)
			return;
		if (!atomic_compare_exchange_weak(&w->ticket, &t, t + 1))
			continue;  // t now holds the ticket as it is
		if (helper)
			fesetenv(&w->environment);
		w->job(w->context, (int)next);
		if (helper) {
			const int flags = fetestexcept(FE_ALL_EXCEPT);
			if (flags != 0)
				atomic_fetch_or_explicit(&w->raised, flags, memory_order_relaxed);
		}
		atomic_fetch_add_explicit(&w->done, 1, memory_order_release);
		t = atomic_load(&w->ticket);
	}
}

static void* helper_main(void* argument)
{
	struct sm_workers* w = ((helper*)argument)->team;
	unsigned seen = 0;
	for (;;) {
		unsigned g = generation_of(atomic_load_explicit(&w->ticket, memory_order_acquire));
		for (int spins = 0; g == seen && spins < SPIN_LIMIT; spins++) {
			relax(spins);
			g = generation_of(atomic_load_explicit(&w->ticket, memory_order_acquire));
		}
		if (g == seen) {
			pthread_mutex_lock(&w->lock);
			atomic_fetch_add(&w->sleeping, 1);
			while ((g = generation_of(atomic_load(&w->ticket))) == seen)
				pthread_cond_wait(&w->wake, &w->lock);
			atomic_fetch_sub(&w->sleeping, 1);
			pthread_mutex_unlock(&w->lock);
		}
		seen = g;
		if (atomic_load(&w->stop))
			return NULL;
		claim_chunks(w, true);
	}
}

// Publishes a job of `chunks` chunks (0 with stop set: the end), whose fields the caller has set,
// and wakes sleeping helpers.
static void publish(struct sm_workers* w, int chunks)
{
	const uint_least64_t generation = generation_of(atomic_load(&w->ticket)) + 1u;
	atomic_store(&w->ticket, (generation & 0xffffffffu) << 32 | (uint_least64_t)chunks << 16);
	if (atomic_load(&w->sleeping) > 0) {
		pthread_mutex_lock(&w->lock);
		pthread_cond_broadcast(&w->wake);
		pthread_mutex_unlock(&w->lock);
	}
}

int sm_workers_processors(void)
{
#ifdef CPU_COUNT
	cpu_set_t set;
	if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
		return CPU_COUNT(&set);
#endif
	const long online = sysconf(_SC_NPROCESSORS_ONLN);
	return online > 0 ? (online < 1024 ? (int)online : 1024) : 1;
}

void sm_workers_destroy(sm_workers* w)
{
	if (w == NULL)
		return;
	// A child of fork() has none of the helpers (sm_workers_run): there is nothing to stop or join
	// (joining a thread of the parent waits for ever), and the lock and the condition variable are
	// as the parent's helpers left them (a sleeping helper counts as a waiter, which destroying
	// the condition variable would wait for). Only the memory is the child's to free.
	if (w->process == getpid()) {
		atomic_store(&w->stop, true);
		publish(w, 0);
		for (int t = 0; t < w->started; t++)
			pthread_join(w->helpers[t].thread, NULL);
		pthread_cond_destroy(&w->wake);
		pthread_mutex_destroy(&w->lock);
	}
	free(w->helpers);
	free(w);
}

sm_workers* sm_workers_create(int threads)
{
	if (threads < 2)
		return NULL;
	struct sm_workers* w = calloc(1, sizeof *w);
	if (w == NULL)
		return NULL;
	w->helpers = calloc((size_t)threads - 1, sizeof(helper));
	if (w->helpers == NULL || pthread_mutex_init(&w->lock, NULL) != 0) {
		free(w->helpers);
		free(w);
		return NULL;
	}
	if (pthread_cond_init(&w->wake, NULL) != 0) {
		pthread_mutex_destroy(&w->lock);
		free(w->helpers);
		free(w);
		return NULL;
	}
	w->threads = threads;
	w->process = getpid();
	atomic_init(&w->ticket, 0);
	atomic_init(&w->done, 0);
	atomic_init(&w->sleeping, 0);
	atomic_init(&w->stop, false);
	atomic_init(&w->raised, 0);
	// The helpers block every signal (a thread starts with its creator's mask), so that signals
	// for the process go to the program's own threads, whose handlers expect them.
	sigset_t all, old;
	sigfillset(&all);
	pthread_sigmask(SIG_SETMASK, &all, &old);
	for (int t = 0; t < threads - 1; t++) {
		w->helpers[t].team = w;
		if (pthread_create(&w->helpers[t].thread, NULL, helper_main, &w->helpers[t]) != 0)
			break;
		w->started++;
	}
	pthread_sigmask(SIG_SETMASK, &old, NULL);
	if (w->started < threads - 1) {
		sm_workers_destroy(w);
		return NULL;
	}
	return w;
}

void sm_workers_run(sm_workers* w, sm_worker_job job, void* context, int chunks)
{
	// A child of fork() has none of its parent's helpers: it runs the chunks itself, as does a
	// job of more chunks than the ticket counts.
	if (w == NULL || w->process != getpid() || chunks > MAX_CHUNKS) {
		for (int c = 0; c < chunks; c++)
			job(context, c);
		return;
	}
	if (chunks <= 0)
		return;
	w->job = job;
	w->context = context;
	fegetenv(&w->environment);
	atomic_store_explicit(&w->done, 0, memory_order_relaxed);
	atomic_store_explicit(&w->raised, 0, memory_order_relaxed);
	publish(w, chunks);
	claim_chunks(w, false);
	for (int polls = 0; atomic_load_explicit(&w->done, memory_order_acquire) < chunks; polls++)
		relax(polls);
	// Every helper's flags were added before its chunk counted as done. Only those the caller
	// has not raised yet (inexact results, the common case, are raised in every job).
	const int raised = atomic_load_explicit(&w->raised, memory_order_relaxed) & ~fetestexcept(FE_ALL_EXCEPT);
	if (raised != 0)
		feraiseexcept(raised);
}

// A team of threads for the chunks of one job at a time (workers.h).
//
// Hand-off. The caller stores the job, then increments `generation` (sequentially consistent);
// a helper that sees the new generation (acquire) sees the job too. A helper about to sleep
// counts itself in `sleeping` and checks the generation again under the lock, and the caller
// reads `sleeping` after its increment: of the two sequentially consistent operations one sees
// the other, so either the helper sees the new generation or the caller sees it sleeping and
// wakes it under the lock. Completion: each helper decrements `pending` (release) after its
// chunks, and the caller spins until it reads 0 (acquire), which makes the helpers' writes
// visible to it.
//
// Floating-point environment. A thread starts with the environment of the thread that created
// it, and the caller's may change after that (its rounding mode, flushing of subnormals), or the
// caller may be another thread: the caller stores its environment with each job and the helpers
// take it before their chunks, so that a chunk gives the same bits on whichever thread runs it.
#define _GNU_SOURCE  // sched_getaffinity, CPU_COUNT

#include "workers.h"

#include <fenv.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

// Polls of the generation before a helper sleeps: about 50 - 100 us on current x86-64
// processors, longer than the gap between the jobs of one conjugate-gradient iteration, much
// shorter than that between two simulation calls. Every YIELD_EVERY polls a waiting thread
// (helper or caller) yields its processor, so that a thread it waits for gets to run when there
// are more threads than processors.
#define SPIN_LIMIT 20000
#define YIELD_EVERY 1024

typedef struct helper {
	struct sm_workers* team;
	int index;  // 1 .. threads - 1
	pthread_t thread;
} helper;

struct sm_workers {
	int threads;  // the caller's included
	int started;  // helpers running
	helper* helpers;
	pthread_mutex_t lock;
	pthread_cond_t wake;
	atomic_uint generation;
	atomic_int pending;
	atomic_int sleeping;
	bool stop;
	sm_worker_job job;
	void* context;
	int chunks;
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

static void run_chunks(struct sm_workers* w, int index)
{
	for (int c = index; c < w->chunks; c += w->threads)
		w->job(w->context, c);
}

static void* helper_main(void* argument)
{
	helper* h = argument;
	struct sm_workers* w = h->team;
	unsigned seen = 0;
	for (;;) {
		unsigned g = atomic_load_explicit(&w->generation, memory_order_acquire);
		for (int spins = 0; g == seen && spins < SPIN_LIMIT; spins++) {
			relax(spins);
			g = atomic_load_explicit(&w->generation, memory_order_acquire);
		}
		if (g == seen) {
			pthread_mutex_lock(&w->lock);
			atomic_fetch_add(&w->sleeping, 1);
			while ((g = atomic_load(&w->generation)) == seen)
				pthread_cond_wait(&w->wake, &w->lock);
			atomic_fetch_sub(&w->sleeping, 1);
			pthread_mutex_unlock(&w->lock);
		}
		seen = g;
		if (w->stop)
			return NULL;
		fesetenv(&w->environment);
		run_chunks(w, h->index);
		atomic_fetch_sub_explicit(&w->pending, 1, memory_order_release);
	}
}

// Publishes the job (or the stop) set by the caller and wakes sleeping helpers.
static void publish(struct sm_workers* w)
{
	atomic_fetch_add(&w->generation, 1);
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
	w->stop = true;
	publish(w);
	for (int t = 0; t < w->started; t++)
		pthread_join(w->helpers[t].thread, NULL);
	pthread_cond_destroy(&w->wake);
	pthread_mutex_destroy(&w->lock);
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
	atomic_init(&w->generation, 0);
	atomic_init(&w->pending, 0);
	atomic_init(&w->sleeping, 0);
	for (int t = 0; t < threads - 1; t++) {
		w->helpers[t] = (helper){.team = w, .index = t + 1};
		if (pthread_create(&w->helpers[t].thread, NULL, helper_main, &w->helpers[t]) != 0) {
			sm_workers_destroy(w);
			return NULL;
		}
		w->started++;
	}
	return w;
}

void sm_workers_run(sm_workers* w, sm_worker_job job, void* context, int chunks)
{
	// A child of fork() has none of its parent's helpers: it runs the chunks itself.
	if (w == NULL || w->process != getpid()) {
		for (int c = 0; c < chunks; c++)
			job(context, c);
		return;
	}
	w->job = job;
	w->context = context;
	w->chunks = chunks;
	fegetenv(&w->environment);
	atomic_store(&w->pending, w->threads - 1);
	publish(w);
	run_chunks(w, 0);
	for (int polls = 0; atomic_load_explicit(&w->pending, memory_order_acquire) > 0; polls++)
		relax(polls);
}

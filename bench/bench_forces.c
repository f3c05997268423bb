// Force evaluation benchmark over the benchmark cloth (bench/README.md): springs evaluated per
// second by the physics core's evaluation functions.
//
//   bench_forces N [TRIALS]
//
// prints, for the n x n cloth, one line per kind of evaluation:
//   <kind> n=<n> springs=<S> springs_per_s=<median> best_springs_per_s=<best>
// with the kinds
//   forces           sm_model_forces
//   forces+jacobian  sm_model_forces_and_jacobians (exact variant): the forces and every
//                    spring's df/dx and df/dv blocks in factored form, in one pass
//   forces+csr       the same, then sm_sparse_jacobian_fill_from_springs of both sparse
//                    matrices from the per-spring data
//   forces+fill      sm_model_forces, then sm_sparse_jacobian_fill of both sparse matrices
//                    (geometry evaluated again from x and v)
// The median is over TRIALS trials (default 7), each timing enough repetitions for ~0.1 s; the
// kinds take turns within each trial, so that a noisy neighbour slows them alike.
// The state is the one the reference kernel uses: the flat cloth perturbed by 1e-3 m, with
// small velocities, so that no spring sits exactly at rest.
#define _POSIX_C_SOURCE 199309L
#include "bench_args.h"
#include "bench_clock.h"
#include "springmass/model.h"
#include "springmass/structures.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

// The benchmark cloth: sm_add_sheet's defaults are its constants (per-strain E = 1000 N for
// structural and shear springs, 50 N for bend springs, c = 2 N s, 1 kg), and its particles and
// springs come in the reference order; the two corners at y = 1 are fixed.
static sm_model* cloth(int n)
{
	sm_model_def md = sm_default_model_def();
	md.particle_capacity = n * n;
	md.spring_capacity = 6 * n * n;
	sm_model* m = sm_model_create(&md, NULL);
	if (m == NULL)
		return NULL;
	sm_sheet_def sheet = sm_default_sheet_def();
	sheet.nu = sheet.nv = n;
	sm_structure st;
	if (sm_add_sheet(m, &sheet, &st) != SM_OK ||
	    sm_set_motion_at(m, &st, n - 1, 0, 0, SM_PARTICLE_FIXED) != SM_OK ||
	    sm_set_motion_at(m, &st, n - 1, n - 1, 0, SM_PARTICLE_FIXED) != SM_OK) {
		fprintf(stderr, "bench_forces: %s\n", sm_model_last_error(m));
		sm_model_destroy(m);
		return NULL;
	}
	return m;
}

enum { FORCES, FORCES_JACOBIAN, FORCES_CSR, FORCES_FILL, KINDS };
static const char* const kind_name[KINDS] = {"forces", "forces+jacobian", "forces+csr", "forces+fill"};

typedef struct workload {
	sm_model* model;
	sm_sparse_jacobian* pattern;
	sm_spring_jacobians* springs;
	const double *x, *v;
	double *f, *jx, *jv;
} workload;

static void evaluate(const workload* w, int kind)
{
	switch (kind) {
	case FORCES: sm_model_forces(w->model, w->x, w->v, NULL, w->f); break;
	case FORCES_JACOBIAN:
		sm_model_forces_and_jacobians(w->model, w->x, w->v, NULL, SM_JACOBIAN_EXACT, w->f, w->springs);
		break;
	case FORCES_CSR:
		sm_model_forces_and_jacobians(w->model, w->x, w->v, NULL, SM_JACOBIAN_EXACT, w->f, w->springs);
		sm_sparse_jacobian_fill_from_springs(w->pattern, w->model, w->springs, w->jx, w->jv);
		break;
	default:
		sm_model_forces(w->model, w->x, w->v, NULL, w->f);
		sm_sparse_jacobian_fill(w->pattern, w->model, w->x, w->v, SM_JACOBIAN_EXACT, w->jx, w->jv);
		break;
	}
}

// Seconds per evaluation over `reps` repetitions.
static double time_kind(const workload* w, int kind, long reps)
{
	const double t0 = bench_now();
	for (long r = 0; r < reps; r++)
		evaluate(w, kind);
	return (bench_now() - t0) / (double)reps;
}

int main(int argc, char** argv)
{
	int n = 128, trials = 7;
	if ((argc > 1 && !bench_read_count(argv[1], 3, 4096, &n)) ||
	    (argc > 2 && !bench_read_count(argv[2], 1, 1000, &trials))) {
		fprintf(stderr, "usage: bench_forces N [TRIALS] (N from 3 to 4096, TRIALS from 1 to 1000)\n");
		return 2;
	}
	workload w = {0};
	w.model = cloth(n);
	w.pattern = w.model != NULL ? sm_sparse_jacobian_create(w.model) : NULL;
	w.springs = w.model != NULL ? sm_spring_jacobians_create(w.model) : NULL;
	const int N = n * n;
	const size_t nnz = (size_t)sm_sparse_jacobian_nonzeros(w.pattern);
	double* x = malloc(3 * (size_t)N * sizeof(double));
	double* v = malloc(3 * (size_t)N * sizeof(double));
	w.f = malloc(3 * (size_t)N * sizeof(double));
	w.jx = malloc((nnz + 1) * sizeof(double));
	w.jv = malloc((nnz + 1) * sizeof(double));
	double* times = malloc((size_t)KINDS * (size_t)trials * sizeof(double));
	if (w.pattern == NULL || w.springs == NULL || x == NULL || v == NULL || w.f == NULL || w.jx == NULL ||
	    w.jv == NULL || times == NULL) {
		fprintf(stderr, "bench_forces: out of memory\n");
		return 1;
	}
	const int S = sm_model_spring_count(w.model);
	const double h = 1.0 / (n - 1);
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			const int p = i * n + j;
			x[3 * p] = j * h + 1e-3 * sin(p);
			x[3 * p + 1] = i * h;
			x[3 * p + 2] = 1e-3 * cos(p);
			v[3 * p] = v[3 * p + 1] = v[3 * p + 2] = 0.01 * sin(3.0 * p);
		}
	w.x = x;
	w.v = v;
	// Repetitions for about 0.1 s per trial and kind, from a calibration run.
	long reps[KINDS];
	for (int k = 0; k < KINDS; k++) {
		reps[k] = 1;
		while (reps[k] < (1L << 24) && reps[k] * time_kind(&w, k, reps[k]) < 0.02)
			reps[k] *= 2;
		reps[k] *= 5;
	}
	double checksum = 0.0;
	for (int t = 0; t < trials; t++)
		for (int k = 0; k < KINDS; k++) {
			times[k * trials + t] = time_kind(&w, k, reps[k]);
			checksum += w.f[3 * (N / 2)] + w.jx[nnz / 2];
		}
	for (int k = 0; k < KINDS; k++) {
		double* tk = times + k * trials;
		const double median = bench_median(tk, trials);  // tk sorted: tk[0] is the best
		printf("%s n=%d springs=%d springs_per_s=%.4e best_springs_per_s=%.4e\n", kind_name[k], n, S,
		       S / median, S / tk[0]);
	}
	fprintf(stderr, "checksum %.6e\n", checksum);
	free(x);
	free(v);
	free(w.f);
	free(w.jx);
	free(w.jv);
	free(times);
	sm_spring_jacobians_destroy(w.springs);
	sm_sparse_jacobian_destroy(w.pattern);
	sm_model_destroy(w.model);
	return 0;
}

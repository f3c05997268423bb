// Force evaluation benchmark over the benchmark cloth (bench/README.md): springs evaluated per
// second by sm_model_forces, and by sm_model_forces plus the sparse fill of df/dx and df/dv.
//
//   bench_forces N [TRIALS]
//
// prints, for the n x n cloth,
//   forces n=<n> springs=<S> springs_per_s=<median> best_springs_per_s=<best>
//   forces+jacobian n=<n> springs=<S> springs_per_s=<median> best_springs_per_s=<best>
// The median is over TRIALS trials (default 7), each timing enough repetitions for ~0.1 s.
// The state is the one the reference kernel uses: the flat cloth perturbed by 1e-3 m, with
// small velocities, so that no spring sits exactly at rest.
#define _POSIX_C_SOURCE 199309L
#include "springmass/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int compare_double(const void* a, const void* b)
{
	const double x = *(const double*)a, y = *(const double*)b;
	return (x > y) - (x < y);
}

// The benchmark cloth, particles and springs in the reference order.
static sm_model* cloth(int n)
{
	sm_model_def md = sm_default_model_def();
	md.particle_capacity = n * n;
	md.spring_capacity = 6 * n * n;
	sm_model* m = sm_model_create(&md, NULL);
	if (m == NULL)
		return NULL;
	const double h = 1.0 / (n - 1);
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			sm_particle_def p = sm_default_particle_def();
			p.mass = 1.0 / ((double)n * n);
			p.position[0] = j * h;
			p.position[1] = i * h;
			p.motion = (i == n - 1 && (j == 0 || j == n - 1)) ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
			if (sm_model_add_particle(m, &p, NULL) != SM_OK)
				goto fail;
		}
	static const int offset[6][2] = {{0, 1}, {1, 0}, {1, 1}, {1, -1}, {0, 2}, {2, 0}};
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			for (int o = 0; o < 6; o++) {
				const int a = i + offset[o][0], b = j + offset[o][1];
				if (a < 0 || a >= n || b < 0 || b >= n)
					continue;
				sm_spring_def d = sm_default_spring_def();
				d.a = i * n + j;
				d.b = a * n + b;
				d.stiffness = o < 4 ? 1000.0 : 50.0;
				d.stiffness_scaling = SM_PER_STRAIN;
				d.damping = 2.0;
				d.damping_scaling = SM_PER_STRAIN;
				if (sm_model_add_spring(m, &d, NULL) != SM_OK)
					goto fail;
			}
	return m;
fail:
	sm_model_destroy(m);
	return NULL;
}

int main(int argc, char** argv)
{
	const int n = argc > 1 ? atoi(argv[1]) : 128;
	const int trials = argc > 2 ? atoi(argv[2]) : 7;
	if (n < 3 || trials < 1) {
		fprintf(stderr, "usage: bench_forces N [TRIALS] (N >= 3)\n");
		return 2;
	}
	sm_model* m = cloth(n);
	sm_sparse_jacobian* J = m != NULL ? sm_sparse_jacobian_create(m) : NULL;
	if (J == NULL) {
		fprintf(stderr, "bench_forces: out of memory\n");
		sm_model_destroy(m);
		return 1;
	}
	const int N = n * n, S = sm_model_spring_count(m);
	const size_t nnz = (size_t)sm_sparse_jacobian_nonzeros(J);
	double* x = malloc(3 * (size_t)N * sizeof(double));
	double* v = malloc(3 * (size_t)N * sizeof(double));
	double* f = malloc(3 * (size_t)N * sizeof(double));
	double* jx = malloc(nnz * sizeof(double));
	double* jv = malloc(nnz * sizeof(double));
	double* times = malloc((size_t)trials * sizeof(double));
	const double h = 1.0 / (n - 1);
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			const int p = i * n + j;
			x[3 * p] = j * h + 1e-3 * sin(p);
			x[3 * p + 1] = i * h;
			x[3 * p + 2] = 1e-3 * cos(p);
			v[3 * p] = v[3 * p + 1] = v[3 * p + 2] = 0.01 * sin(3.0 * p);
		}
	double checksum = 0.0;
	for (int pass = 0; pass < 2; pass++) {
		// Repetitions for about 0.1 s per trial, from a calibration run.
		int reps = 1;
		for (;;) {
			const double t0 = now();
			for (int r = 0; r < reps; r++) {
				sm_model_forces(m, x, v, NULL, f);
				if (pass == 1)
					sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, jx, jv);
			}
			if (now() - t0 > 0.02 || reps > (1 << 24))
				break;
			reps *= 2;
		}
		reps *= 5;
		for (int t = 0; t < trials; t++) {
			const double t0 = now();
			for (int r = 0; r < reps; r++) {
				sm_model_forces(m, x, v, NULL, f);
				if (pass == 1)
					sm_sparse_jacobian_fill(J, m, x, v, SM_JACOBIAN_EXACT, jx, jv);
			}
			times[t] = (now() - t0) / reps;
			checksum += f[3 * (N / 2)] + (pass == 1 ? jx[nnz / 2] : 0.0);
		}
		qsort(times, (size_t)trials, sizeof(double), compare_double);
		const double median = times[trials / 2], best = times[0];
		printf("%s n=%d springs=%d springs_per_s=%.4e best_springs_per_s=%.4e\n",
		       pass == 0 ? "forces" : "forces+jacobian", n, S, S / median, S / best);
	}
	fprintf(stderr, "checksum %.6e\n", checksum);
	free(x);
	free(v);
	free(f);
	free(jx);
	free(jv);
	free(times);
	sm_sparse_jacobian_destroy(J);
	sm_model_destroy(m);
	return 0;
}

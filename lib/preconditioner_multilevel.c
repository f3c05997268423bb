// Multilevel approximate inverse of the two-level preconditioner's coarse matrix A_1 = P^T A P.
//
// Why. The exact coarse solve (CHOLMOD) grows faster than the unknowns: on the benchmark cloth
// n = 256 (13 300 coarse unknowns) its triangular solves took as long as the spring products
// (36% and 32% of the run).
// Below A_1 the same aggregation repeats: level l + 1 groups each block of level l with its
// neighbours not yet taken, and its matrix is the Galerkin sum A_{l+1} = P_l^T A_l P_l, P_l
// moving each aggregate as one: block (I', J') is the sum of the blocks (I, J) with I in I' and
// J in J' (the map from every block to its target is built once, here). The coarsest level
// (at most coarsest_dofs unknowns) is factorised by CHOLMOD.
//
// A_1^-1 is replaced by one V-cycle from x = 0: pre-smoothing x = S b, residual, restriction,
// the cycle of the level below, prolongation, post-smoothing x += S (b - A x), with S^-1 the
// l1 block-Jacobi matrix: A's diagonal block plus, on its diagonal, the row's absolute sums over
// the other blocks. S^-1 - A is then diagonally dominant, hence positive semi-definite, so each
// smoothing step is a contraction in the A norm and the cycle (the same S before and after, an
// exact coarsest solve) is a symmetric positive definite operator: block Jacobi + P V P^T stays
// so too. One cycle alone was too inexact for the reduced solver (30% more iterations than the
// exact coarse solve on the benchmark cloth n = 256), so the reduced solver asks for a few
// conjugate-gradient iterations on A_1 preconditioned by the cycle (3: 2% more iterations than
// exact); that makes the preconditioner depend on its argument non-linearly, and the outer
// conjugate gradients flexible. The cycles' products read the matrices in single precision
// (sums and smoother inverses in double; the Galerkin sums cancel the springs inside the
// aggregates, which single precision would not do accurately): in double they took 30% of the
// run at n = 256, as much as the fine spring products.
#define _POSIX_C_SOURCE 200809L

#include "preconditioner_multilevel.h"

#include "cholmod_factorize.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_LEVELS 12

typedef struct level {
	int32_t count;       // block rows
	int64_t* first;      // block row I's neighbours: neighbour[first[I] .. first[I + 1])
	int32_t* neighbour;  // sorted, I itself included
	int32_t* self;       // position of I in its list
	double* values;      // block layout; the top level's are the caller's
	float* matrix;       // the same in single precision, for the cycles' products
	double* smoother;    // per block row: the inverse of its l1 diagonal block (9)
	int32_t* aggregate;  // per block row: its block row on the level below (not on the coarsest)
	int64_t* target;     // per block: first entry of its target block on the level below
	double *b, *x, *r;   // 3 per block row
} level;

struct sm_multilevel {
	int levels;
	level level[MAX_LEVELS];
	cholmod_sparse* coarsest;
	cholmod_factor* factor;
	cholmod_dense *cb, *cx, *cy, *ce;
	double *solution, *residual, *direction, *product;  // top level's conjugate gradients
	sm_workers* workers;                                // of the current solve
};

// The adjugate of a 3x3 block into adj, returning the determinant.
static inline double adjugate3(const double* a, double* adj)
{
	adj[0] = a[4] * a[8] - a[5] * a[7];
	adj[1] = a[2] * a[7] - a[1] * a[8];
	adj[2] = a[1] * a[5] - a[2] * a[4];
	adj[3] = a[5] * a[6] - a[3] * a[8];
	adj[4] = a[0] * a[8] - a[2] * a[6];
	adj[5] = a[2] * a[3] - a[0] * a[5];
	adj[6] = a[3] * a[7] - a[4] * a[6];
	adj[7] = a[1] * a[6] - a[0] * a[7];
	adj[8] = a[0] * a[4] - a[1] * a[3];
	return a[0] * adj[0] + a[1] * adj[3] + a[2] * adj[6];
}

// The adjugate over the determinant. The determinant, a product of three entries, overflows for
// blocks of about 1e102 (a particle of 1e102 kg) and underflows for blocks of about 1e-103; then
// the block is scaled by 2^-e with 2^e near its largest entry: A = 2^e S gives
// A^-1 = 2^-e S^-1, and scaling by a power of two is exact. The common case (a determinant far
// from both limits) takes the direct path, which this scaling would slow by a seventh on the
// benchmark cloth.
bool sm_invert3(const double* a, double* inv)
{
	double det = adjugate3(a, inv);
	if (isfinite(det) && fabs(det) >= 0x1p-600) {
		const double scale = 1.0 / det;
		for (int i = 0; i < 9; i++)
			inv[i] *= scale;
		return true;
	}
	double largest = 0.0;
	for (int i = 0; i < 9; i++)
		largest = fmax(largest, fabs(a[i]));
	if (!(largest > 0.0) || !isfinite(largest))
		return false;
	int e;
	frexp(largest, &e);
	double s[9];
	for (int i = 0; i < 9; i++)
		s[i] = ldexp(a[i], -e);
	det = adjugate3(s, inv);
	if (!(fabs(det) > 0.0) || !isfinite(det))
		return false;
	const double scale = 1.0 / det;
	for (int i = 0; i < 9; i++)
		inv[i] = ldexp(inv[i] * scale, -e);
	return true;
}

void sm_block_pattern_fill(int32_t count, const int64_t* first, const int32_t* neighbour, int64_t* p,
                           int64_t* index)
{
	p[0] = 0;
	for (int32_t I = 0; I < count; I++) {
		const int64_t degree = first[I + 1] - first[I];
		for (int i = 0; i < 3; i++) {
			const int64_t row = 3 * (int64_t)I + i;
			for (int64_t k = 0; k < degree; k++)
				for (int j = 0; j < 3; j++)
					index[sm_block_entry(first, I, (int32_t)k, i, j)] =
					    3 * (int64_t)neighbour[first[I] + k] + j;
			p[row + 1] = sm_block_entry(first, I, 0, i, 0) + 3 * degree;
		}
	}
}

static void level_free(level* l, bool top)
{
	free(l->first);
	free(l->neighbour);
	free(l->self);
	if (!top)
		free(l->values);
	free(l->smoother);
	free(l->matrix);
	free(l->aggregate);
	free(l->target);
	free(l->b);
	free(l->x);
	free(l->r);
}

// Allocates a level's per-row arrays once first and neighbour are set.
static bool level_allocate(level* l, bool top)
{
	const size_t n = (size_t)l->count + 1, blocks = (size_t)l->first[l->count] + 1;
	l->self = malloc(n * sizeof(int32_t));
	l->smoother = malloc(9 * n * sizeof(double));
	l->matrix = malloc(9 * ((size_t)l->first[l->count] + 1) * sizeof(float));
	l->b = calloc(3 * n, sizeof(double));
	l->x = calloc(3 * n, sizeof(double));
	l->r = calloc(3 * n, sizeof(double));
	if (!top)
		l->values = calloc(9 * blocks, sizeof(double));
	if (!l->self || !l->smoother || !l->matrix || !l->b || !l->x || !l->r || (!top && !l->values))
		return false;
	for (int32_t I = 0; I < l->count; I++)
		for (int64_t e = l->first[I]; e < l->first[I + 1]; e++)
			if (l->neighbour[e] == I)
				l->self[I] = (int32_t)(e - l->first[I]);
	return true;
}

// Aggregates the block rows of f (each row whose neighbours are all untaken starts an aggregate
// with them; the rows left join a neighbour's aggregate) and builds the level below, c: its
// pattern (the aggregates linked by a block, sorted, itself included) and every block's target.
// Returns false on out of memory.
static bool coarsen(level* f, level* c)
{
	const int32_t n = f->count;
	int32_t* group = malloc(((size_t)n + 1) * sizeof(int32_t));
	int32_t* taken = malloc(((size_t)n + 1) * sizeof(int32_t));
	f->aggregate = group;
	f->target = malloc(((size_t)f->first[n] + 1) * sizeof(int64_t));
	if (!group || !taken || !f->target) {
		free(taken);
		return false;
	}
	int32_t count = 0;
	for (int32_t I = 0; I < n; I++)
		group[I] = -1;
	for (int32_t I = 0; I < n; I++) {
		bool all_free = group[I] < 0;
		for (int64_t e = f->first[I]; e < f->first[I + 1] && all_free; e++)
			all_free = group[f->neighbour[e]] < 0;
		if (!all_free)
			continue;
		for (int64_t e = f->first[I]; e < f->first[I + 1]; e++)
			group[f->neighbour[e]] = count;
		count++;
	}
	memcpy(taken, group, (size_t)n * sizeof(int32_t));
	for (int32_t I = 0; I < n; I++) {
		for (int64_t e = f->first[I]; e < f->first[I + 1] && group[I] < 0; e++)
			if (taken[f->neighbour[e]] >= 0)
				group[I] = taken[f->neighbour[e]];
		if (group[I] < 0)
			group[I] = count++;
	}
	free(taken);
	c->count = count;
	// Members of each aggregate, then its neighbour list, counted in a first pass, filled in a
	// second.
	int64_t* member_first = calloc((size_t)count + 2, sizeof(int64_t));
	int32_t* member = malloc(((size_t)n + 1) * sizeof(int32_t));
	int32_t* seen = malloc(((size_t)count + 1) * sizeof(int32_t));
	int32_t* list = malloc(((size_t)count + 1) * sizeof(int32_t));
	c->first = calloc((size_t)count + 1, sizeof(int64_t));
	bool ok = member_first && member && seen && list && c->first;
	if (ok) {
		for (int32_t I = 0; I < n; I++)
			member_first[group[I] + 2]++;
		for (int32_t A = 0; A < count; A++)
			member_first[A + 2] += member_first[A + 1];
		for (int32_t I = 0; I < n; I++)
			member[member_first[group[I] + 1]++] = I;
		for (int32_t A = 0; A < count; A++)
			seen[A] = -1;
	}
	for (int pass = 0; pass < 2 && ok; pass++) {
		for (int32_t A = 0; A < count; A++) {
			int32_t degree = 0;
			for (int64_t k = member_first[A]; k < member_first[A + 1]; k++) {
				const int32_t I = member[k];
				for (int64_t e = f->first[I]; e < f->first[I + 1]; e++) {
					const int32_t B = group[f->neighbour[e]];
					if (seen[B] != A) {
						seen[B] = A;
						list[degree++] = B;
					}
				}
			}
			for (int32_t i = 1; i < degree; i++)  // insertion sort: the lists are short
				for (int32_t j = i; j > 0 && list[j - 1] > list[j]; j--) {
					const int32_t t = list[j];
					list[j] = list[j - 1];
					list[j - 1] = t;
				}
			if (pass == 0)
				c->first[A + 1] = degree;
			else
				memcpy(c->neighbour + c->first[A], list, (size_t)degree * sizeof(int32_t));
		}
		for (int32_t A = 0; A < count; A++)
			seen[A] = -1;
		if (pass == 0) {
			for (int32_t A = 0; A < count; A++)
				c->first[A + 1] += c->first[A];
			c->neighbour = malloc(((size_t)c->first[count] + 1) * sizeof(int32_t));
			ok = c->neighbour != NULL;
		}
	}
	free(member_first), free(member), free(seen), free(list);
	if (!ok || !level_allocate(c, false))
		return false;
	// Targets: block (I, J) goes to (group I, group J).
	for (int32_t I = 0; I < n; I++) {
		const int32_t A = group[I];
		for (int64_t e = f->first[I]; e < f->first[I + 1]; e++) {
			const int32_t B = group[f->neighbour[e]];
			int64_t k = c->first[A];
			while (c->neighbour[k] != B)
				k++;
			f->target[e] = sm_block_entry(c->first, A, (int32_t)(k - c->first[A]), 0, 0);
		}
	}
	return true;
}

sm_multilevel* sm_multilevel_create(int32_t count, const int64_t* first, const int32_t* neighbour,
                                    int32_t coarsest_dofs, cholmod_common* common)
{
	sm_multilevel* ml = calloc(1, sizeof *ml);
	if (ml == NULL)
		return NULL;
	level* top = &ml->level[0];
	top->count = count;
	top->first = malloc(((size_t)count + 1) * sizeof(int64_t));
	top->neighbour = malloc(((size_t)first[count] + 1) * sizeof(int32_t));
	ml->levels = 1;
	if (!top->first || !top->neighbour)
		goto fail;
	memcpy(top->first, first, ((size_t)count + 1) * sizeof(int64_t));
	memcpy(top->neighbour, neighbour, (size_t)first[count] * sizeof(int32_t));
	if (!level_allocate(top, true))
		goto fail;
	ml->solution = calloc(3 * (size_t)count + 1, sizeof(double));
	ml->residual = calloc(3 * (size_t)count + 1, sizeof(double));
	ml->direction = calloc(3 * (size_t)count + 1, sizeof(double));
	ml->product = calloc(3 * (size_t)count + 1, sizeof(double));
	if (!ml->solution || !ml->residual || !ml->direction || !ml->product)
		goto fail;
	// Coarsen while the level is too large for the factorisation and the coarsening still
	// reduces it (by a fifth at least).
	while (ml->levels < MAX_LEVELS && 3 * (int64_t)ml->level[ml->levels - 1].count > coarsest_dofs) {
		level* f = &ml->level[ml->levels - 1];
		level* c = &ml->level[ml->levels];
		ml->levels++;
		if (!coarsen(f, c))
			goto fail;
		if (5 * (int64_t)c->count > 4 * (int64_t)f->count)
			break;
	}
	const level* last = &ml->level[ml->levels - 1];
	const size_t nc = 3 * (size_t)last->count, nonzeros = 9 * (size_t)last->first[last->count];
	ml->coarsest = cholmod_l_allocate_sparse(nc, nc, nonzeros, 1, 1, 1, CHOLMOD_REAL, common);
	ml->cb = cholmod_l_allocate_dense(nc, 1, nc, CHOLMOD_REAL, common);
	if (!ml->coarsest || !ml->cb)
		goto fail;
	sm_block_pattern_fill(last->count, last->first, last->neighbour, ml->coarsest->p, ml->coarsest->i);
	// The coarsest matrix is small: a simplicial factorisation (the supernodal one calls BLAS).
	const int supernodal = common->supernodal;
	common->supernodal = CHOLMOD_SIMPLICIAL;
	ml->factor = sm_cholmod_analyze(ml->coarsest, common);
	common->supernodal = supernodal;
	if (ml->factor == NULL)
		goto fail;
	return ml;
fail:
	sm_multilevel_destroy(ml, common);
	return NULL;
}

// The l1 block-Jacobi inverses of a level.
static bool invert_smoother(level* l)
{
	for (int32_t I = 0; I < l->count; I++) {
		const int64_t degree = l->first[I + 1] - l->first[I];
		const double* row = l->values + 9 * l->first[I];
		double a[9];
		for (int i = 0; i < 3; i++) {
			double off = 0.0;
			for (int64_t k = 0; k < degree; k++)
				for (int j = 0; j < 3; j++) {
					const double v = row[3 * degree * i + 3 * k + j];
					if (k == l->self[I])
						a[3 * i + j] = v;
					else
						off += fabs(v);
				}
			a[4 * i] += off;
		}
		if (!sm_invert3(a, l->smoother + 9 * (size_t)I))
			return false;
	}
	return true;
}

bool sm_multilevel_refresh(sm_multilevel* ml, const double* values, cholmod_common* common)
{
	ml->level[0].values = (double*)values;  // read only
	for (int d = 0; d < ml->levels; d++) {
		level* l = &ml->level[d];
		if (d + 1 < ml->levels) {
			// Galerkin sum: every block added to its target on the level below.
			level* c = &ml->level[d + 1];
			memset(c->values, 0, 9 * (size_t)c->first[c->count] * sizeof(double));
			for (int32_t I = 0; I < l->count; I++) {
				const int64_t degree = l->first[I + 1] - l->first[I];
				const int32_t A = l->aggregate[I];
				const int64_t stride = 3 * (c->first[A + 1] - c->first[A]);
				const double* row = l->values + 9 * l->first[I];
				for (int64_t k = 0; k < degree; k++) {
					double* t = c->values + l->target[l->first[I] + k];
					for (int i = 0; i < 3; i++)
						for (int j = 0; j < 3; j++)
							t[stride * i + j] += row[3 * degree * i + 3 * k + j];
				}
			}
			if (!invert_smoother(l))
				return false;
		} else {
			memcpy(ml->coarsest->x, l->values, 9 * (size_t)l->first[l->count] * sizeof(double));
		}
		for (int64_t e = 0; e < 9 * l->first[l->count]; e++)
			l->matrix[e] = (float)l->values[e];
	}
	return sm_cholmod_factorize(ml->coarsest, ml->factor, common) && common->status == CHOLMOD_OK;
}

// Block rows from which a level's products run in chunks on the workers, if there are any:
// level 1 of the benchmark cloth n = 256 (7400 block rows) does, its products taking 0.1 - 0.3 ms.
#define MULTILEVEL_PARALLEL_ROWS 2000
#define MULTILEVEL_PARALLEL_CHUNKS 4

// r = b - A x on a level's block rows begin .. end. The three rows of a block row go together,
// so that each neighbour's x is loaded once; each row's sum keeps its order (the same bits as
// row by row).
static void residual_rows(const level* l, const double* b, const double* x, double* r, int32_t begin,
                          int32_t end)
{
	for (int32_t I = begin; I < end; I++) {
		const int64_t degree = l->first[I + 1] - l->first[I];
		const float* a0 = l->matrix + 9 * l->first[I];
		const float* a1 = a0 + 3 * degree;
		const float* a2 = a1 + 3 * degree;
		const int32_t* nb = l->neighbour + l->first[I];
		double s0 = b[3 * (size_t)I], s1 = b[3 * (size_t)I + 1], s2 = b[3 * (size_t)I + 2];
		for (int64_t k = 0; k < degree; k++) {
			const double* y = x + 3 * (size_t)nb[k];
			const double y0 = y[0], y1 = y[1], y2 = y[2];
			s0 -= a0[3 * k] * y0 + a0[3 * k + 1] * y1 + a0[3 * k + 2] * y2;
			s1 -= a1[3 * k] * y0 + a1[3 * k + 1] * y1 + a1[3 * k + 2] * y2;
			s2 -= a2[3 * k] * y0 + a2[3 * k + 1] * y1 + a2[3 * k + 2] * y2;
		}
		r[3 * (size_t)I] = s0;
		r[3 * (size_t)I + 1] = s1;
		r[3 * (size_t)I + 2] = s2;
	}
}

typedef struct residual_job {
	const level* l;
	const double *b, *x;
	double* r;
} residual_job;

static void residual_chunk(void* context, int c)
{
	const residual_job* j = context;
	const int64_t count = j->l->count;
	residual_rows(j->l, j->b, j->x, j->r, (int32_t)(count * c / MULTILEVEL_PARALLEL_CHUNKS),
	              (int32_t)(count * (c + 1) / MULTILEVEL_PARALLEL_CHUNKS));
}

// r = b - A x on a level (b and r may be the same).
static void residual(const sm_multilevel* ml, const level* l, const double* b, const double* x, double* r)
{
	if (ml->workers == NULL || l->count < MULTILEVEL_PARALLEL_ROWS) {
		residual_rows(l, b, x, r, 0, l->count);
		return;
	}
	residual_job job = {l, b, x, r};
	sm_workers_run(ml->workers, residual_chunk, &job, MULTILEVEL_PARALLEL_CHUNKS);
}

// x += S r on a level (x = S r if set).
static void smooth(const level* l, const double* r, double* x, bool set)
{
	for (int32_t I = 0; I < l->count; I++) {
		const double* m = l->smoother + 9 * (size_t)I;
		const double* a = r + 3 * (size_t)I;
		double* o = x + 3 * (size_t)I;
		for (int i = 0; i < 3; i++) {
			const double v = m[3 * i] * a[0] + m[3 * i + 1] * a[1] + m[3 * i + 2] * a[2];
			o[i] = set ? v : o[i] + v;
		}
	}
}

// x = V b on level d (into l->x, from l->b).
static bool cycle(sm_multilevel* ml, int d, cholmod_common* common)
{
	level* l = &ml->level[d];
	if (d + 1 == ml->levels) {
		memcpy(ml->cb->x, l->b, 3 * (size_t)l->count * sizeof(double));
		if (!sm_cholmod_solve(ml->factor, ml->cb, &ml->cx, &ml->cy, &ml->ce, common))
			return false;
		memcpy(l->x, ml->cx->x, 3 * (size_t)l->count * sizeof(double));
		return true;
	}
	level* c = &ml->level[d + 1];
	smooth(l, l->b, l->x, true);
	residual(ml, l, l->b, l->x, l->r);
	memset(c->b, 0, 3 * (size_t)c->count * sizeof(double));
	for (int32_t I = 0; I < l->count; I++)
		for (int i = 0; i < 3; i++)
			c->b[3 * (size_t)l->aggregate[I] + i] += l->r[3 * (size_t)I + i];
	if (!cycle(ml, d + 1, common))
		return false;
	for (int32_t I = 0; I < l->count; I++)
		for (int i = 0; i < 3; i++)
			l->x[3 * (size_t)I + i] += c->x[3 * (size_t)l->aggregate[I] + i];
	residual(ml, l, l->b, l->x, l->r);
	smooth(l, l->r, l->x, false);
	return true;
}

const double* sm_multilevel_solve(sm_multilevel* ml, const double* b, int iterations, sm_workers* workers,
                                  cholmod_common* common)
{
	ml->workers = workers;
	level* top = &ml->level[0];
	const size_t n = 3 * (size_t)top->count;
	memcpy(top->b, b, n * sizeof(double));
	if (!cycle(ml, 0, common))
		return NULL;
	if (iterations <= 1)
		return top->x;
	// Conjugate gradients on the top level preconditioned by the cycle, from x = 0: the
	// solution in ml->solution, the residual in ml->residual, p and q = A p.
	double *x = ml->solution, *res = ml->residual, *p = ml->direction, *q = ml->product;
	memcpy(res, b, n * sizeof(double));
	memset(x, 0, n * sizeof(double));
	memcpy(p, top->x, n * sizeof(double));
	double rz = 0.0;
	for (size_t i = 0; i < n; i++)
		rz += res[i] * top->x[i];
	for (int it = 1; it <= iterations && rz > 0.0; it++) {
		memset(q, 0, n * sizeof(double));
		residual(ml, top, q, p, q);  // q = -A p
		double pq = 0.0;
		for (size_t i = 0; i < n; i++)
			pq -= p[i] * q[i];
		if (!(pq > 0.0))
			break;
		const double alpha = rz / pq;
		for (size_t i = 0; i < n; i++) {
			x[i] += alpha * p[i];
			res[i] += alpha * q[i];
		}
		if (it == iterations)
			break;
		memcpy(top->b, res, n * sizeof(double));
		if (!cycle(ml, 0, common))
			return NULL;
		double rz_next = 0.0;
		for (size_t i = 0; i < n; i++)
			rz_next += res[i] * top->x[i];
		const double beta = rz_next / rz;
		rz = rz_next;
		for (size_t i = 0; i < n; i++)
			p[i] = top->x[i] + beta * p[i];
	}
	return x;
}

void sm_multilevel_destroy(sm_multilevel* ml, cholmod_common* common)
{
	if (ml == NULL)
		return;
	for (int d = 0; d < ml->levels; d++)
		level_free(&ml->level[d], d == 0);
	cholmod_l_free_sparse(&ml->coarsest, common);
	cholmod_l_free_factor(&ml->factor, common);
	cholmod_l_free_dense(&ml->cb, common);
	cholmod_l_free_dense(&ml->cx, common);
	cholmod_l_free_dense(&ml->cy, common);
	cholmod_l_free_dense(&ml->ce, common);
	free(ml->solution);
	free(ml->residual);
	free(ml->direction);
	free(ml->product);
	free(ml);
}

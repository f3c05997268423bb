// Triangular solves with a coarse factor split into two halves and a separator (coarse_halves.h).
//
// CHOLMOD's supernodal factor L: supernode s holds columns super[s] .. super[s + 1] - 1 of L,
// its rows s[pi[s]] .. s[pi[s + 1] - 1] (the first ones those same columns), its values at
// x[px[s]] column by column, nrow = pi[s + 1] - pi[s] to a column: a dense lower triangle on top
// of a dense block of the rows below. A supernode whose columns all lie in one half is solved on
// that half's thread; the others (the separator's, and any that mix a half's columns with the
// separator's) on the caller's, after the halves in the forward solve and before them in the
// backward one. CHOLMOD postorders the elimination tree after the constrained ordering, which
// may interleave the two halves' columns, but no column gains a row of the other half (fill joins
// only unknowns already joined through eliminated ones), and that is all the split needs.
#include "coarse_halves.h"

#include <stdlib.h>
#include <string.h>

struct sm_coarse_halves {
	int64_t n;
	int8_t* column_part;      // per column of L (pivot order): 0 or 1 (a half) or 2 (separator)
	int64_t* supernodes;      // of half 0, then of half 1, then the others, each group in order
	int64_t group[4];         // group g is supernodes[group[g] .. group[g + 1]]
	int64_t* separator_rows;  // the columns of part 2
	int64_t separator_count;
	double* y;             // the vector being solved, in pivot order
	double* separator[2];  // per half: its updates to separator rows (zero at the others)
	double* scratch[2];    // per half: the rows below one supernode's triangle
};

void sm_coarse_halves_destroy(sm_coarse_halves* h)
{
	if (h == NULL)
		return;
	free(h->column_part);
	free(h->supernodes);
	free(h->separator_rows);
	free(h->y);
	for (int k = 0; k < 2; k++) {
		free(h->separator[k]);
		free(h->scratch[k]);
	}
	free(h);
}

sm_coarse_halves* sm_coarse_halves_create(cholmod_sparse* A, const int8_t* part, cholmod_factor** factor,
                                          cholmod_common* common)
{
	*factor = NULL;
	const int64_t n = (int64_t)A->nrow;
	sm_coarse_halves* h = calloc(1, sizeof *h);
	SuiteSparse_long* member = malloc(((size_t)n + 1) * sizeof(SuiteSparse_long));
	SuiteSparse_long* order = malloc(((size_t)n + 1) * sizeof(SuiteSparse_long));
	if (h == NULL || member == NULL || order == NULL)
		goto fail;
	h->n = n;
	for (int64_t i = 0; i < n; i++)
		member[i] = part[i];
	// CAMD orders the constraint sets one after the other (0, 1, then the separator), each for
	// little fill; the analysis takes that ordering as given.
	if (!cholmod_l_camd(A, NULL, 0, member, order, common))
		goto fail;
	const int methods = common->nmethods, ordering = common->method[0].ordering,
	          supernodal = common->supernodal;
	common->nmethods = 1;
	common->method[0].ordering = CHOLMOD_GIVEN;
	common->supernodal = CHOLMOD_SUPERNODAL;
	*factor = cholmod_l_analyze_p(A, order, NULL, 0, common);
	common->nmethods = methods;
	common->method[0].ordering = ordering;
	common->supernodal = supernodal;
	if (*factor == NULL || !(*factor)->is_super)
		goto fail;
	const cholmod_factor* L = *factor;
	const SuiteSparse_long* perm = L->Perm;
	const SuiteSparse_long* super = L->super;
	const int64_t nsuper = (int64_t)L->nsuper;
	h->column_part = malloc(((size_t)n + 1) * sizeof(int8_t));
	h->supernodes = malloc(((size_t)nsuper + 1) * sizeof(int64_t));
	h->separator_rows = malloc(((size_t)n + 1) * sizeof(int64_t));
	h->y = malloc(((size_t)n + 1) * sizeof(double));
	for (int k = 0; k < 2; k++) {
		h->separator[k] = calloc((size_t)n + 1, sizeof(double));
		h->scratch[k] = malloc((L->maxesize + 1) * sizeof(double));
	}
	if (!h->column_part || !h->supernodes || !h->separator_rows || !h->y || !h->separator[0] ||
	    !h->separator[1] || !h->scratch[0] || !h->scratch[1])
		goto fail;
	for (int64_t k = 0; k < n; k++) {
		h->column_part[k] = part[perm[k]];
		if (h->column_part[k] == 2)
			h->separator_rows[h->separator_count++] = k;
	}
	// The groups, each in supernode order (a counting sort by part; member serves as the parts).
	int64_t next[3] = {0, 0, 0};
	for (int64_t s = 0; s < nsuper; s++) {
		int part_of_s = h->column_part[super[s]];
		for (SuiteSparse_long k = super[s] + 1; k < super[s + 1]; k++)
			if (h->column_part[k] != part_of_s)
				part_of_s = 2;
		member[s] = part_of_s;
		next[part_of_s]++;
	}
	h->group[1] = next[0];
	h->group[2] = next[0] + next[1];
	h->group[3] = nsuper;
	for (int g = 0; g < 3; g++)
		next[g] = h->group[g];
	for (int64_t s = 0; s < nsuper; s++)
		h->supernodes[next[member[s]]++] = s;
	free(member);
	free(order);
	return h;
fail:
	cholmod_l_free_factor(factor, common);
	free(member);
	free(order);
	sm_coarse_halves_destroy(h);
	return NULL;
}

// a . b over n entries, in four partial sums (added in a fixed order).
static double dot(const double* restrict a, const double* restrict b, int64_t n)
{
	double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
	int64_t i = 0;
	for (; i + 4 <= n; i += 4) {
		s0 += a[i] * b[i];
		s1 += a[i + 1] * b[i + 1];
		s2 += a[i + 2] * b[i + 2];
		s3 += a[i + 3] * b[i + 3];
	}
	for (; i < n; i++)
		s0 += a[i] * b[i];
	return (s0 + s1) + (s2 + s3);
}

// Supernode s of L: its first column, its column and row counts, its values (column by column,
// `rows` to a column) and its row indices.
typedef struct supernode {
	int64_t first, columns, rows;
	const double* values;
	const SuiteSparse_long* row;
} supernode;

static supernode supernode_of(const cholmod_factor* L, int64_t s)
{
	const SuiteSparse_long* super = L->super;
	const SuiteSparse_long* pi = L->pi;
	const SuiteSparse_long* px = L->px;
	return (supernode){super[s], super[s + 1] - super[s], pi[s + 1] - pi[s], (const double*)L->x + px[s],
	                   (const SuiteSparse_long*)L->s + pi[s]};
}

// Forward solve with supernode s: its triangle in place on y, then its rows below updated, into
// `separator` for separator rows when a half solves it (NULL: the caller's, directly into y).
static void forward_supernode(const sm_coarse_halves* h, const cholmod_factor* L, int64_t s,
                              double* restrict y, double* restrict separator, double* restrict below)
{
	const supernode n = supernode_of(L, s);
	const int64_t columns = n.columns, rows = n.rows, below_count = rows - columns;
	const double* values = n.values;
	const SuiteSparse_long* row = n.row;
	double* ys = y + n.first;
	for (int64_t j = 0; j < columns; j++) {
		const double* c = values + j * rows;
		const double v = ys[j] / c[j];
		ys[j] = v;
		for (int64_t i = j + 1; i < columns; i++)
			ys[i] -= c[i] * v;
	}
	if (below_count == 0)
		return;
	memset(below, 0, (size_t)below_count * sizeof(double));
	for (int64_t j = 0; j < columns; j++) {
		const double* c = values + j * rows + columns;
		const double v = ys[j];
		for (int64_t i = 0; i < below_count; i++)
			below[i] += c[i] * v;
	}
	for (int64_t i = 0; i < below_count; i++) {
		const int64_t r = row[columns + i];
		if (separator != NULL && h->column_part[r] == 2)
			separator[r] -= below[i];
		else
			y[r] -= below[i];
	}
}

// Backward solve with supernode s: its columns of y from the rows below, already solved.
static void backward_supernode(const cholmod_factor* L, int64_t s, double* restrict y, double* restrict below)
{
	const supernode n = supernode_of(L, s);
	const int64_t columns = n.columns, rows = n.rows, below_count = rows - columns;
	const double* values = n.values;
	const SuiteSparse_long* row = n.row;
	double* ys = y + n.first;
	for (int64_t i = 0; i < below_count; i++)
		below[i] = y[row[columns + i]];
	for (int64_t j = columns - 1; j >= 0; j--) {
		const double* c = values + j * rows;
		const double sum =
		    ys[j] - dot(c + j + 1, ys + j + 1, columns - j - 1) - dot(c + columns, below, below_count);
		ys[j] = sum / c[j];
	}
}

typedef struct half_job {
	sm_coarse_halves* h;
	const cholmod_factor* L;
} half_job;

static void forward_half(void* context, int half)
{
	const half_job* j = context;
	sm_coarse_halves* h = j->h;
	double* separator = h->separator[half];
	for (int64_t k = 0; k < h->separator_count; k++)
		separator[h->separator_rows[k]] = 0.0;
	for (int64_t g = h->group[half]; g < h->group[half + 1]; g++)
		forward_supernode(h, j->L, h->supernodes[g], h->y, separator, h->scratch[half]);
}

static void backward_half(void* context, int half)
{
	const half_job* j = context;
	sm_coarse_halves* h = j->h;
	for (int64_t g = h->group[half + 1] - 1; g >= h->group[half]; g--)
		backward_supernode(j->L, h->supernodes[g], h->y, h->scratch[half]);
}

void sm_coarse_halves_solve(sm_coarse_halves* h, const cholmod_factor* L, const double* b, double* x,
                            sm_workers* workers)
{
	const SuiteSparse_long* perm = L->Perm;
	double* y = h->y;
	for (int64_t k = 0; k < h->n; k++)
		y[k] = b[perm[k]];
	half_job job = {h, L};
	sm_workers_run(workers, forward_half, &job, 2);
	for (int64_t k = 0; k < h->separator_count; k++) {
		const int64_t r = h->separator_rows[k];
		y[r] += h->separator[0][r] + h->separator[1][r];
	}
	for (int64_t g = h->group[2]; g < h->group[3]; g++)
		forward_supernode(h, L, h->supernodes[g], y, NULL, h->scratch[0]);
	for (int64_t g = h->group[3] - 1; g >= h->group[2]; g--)
		backward_supernode(L, h->supernodes[g], y, h->scratch[0]);
	sm_workers_run(workers, backward_half, &job, 2);
	for (int64_t k = 0; k < h->n; k++)
		x[perm[k]] = y[k];
}

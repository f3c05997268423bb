// The edges of a triangle mesh (see mesh_edges.h).
#include "mesh_edges.h"

#include "keyed_hash.h"

#include <stdlib.h>
#include <string.h>

bool sm_mesh_edges_init(mesh_edges* edges, int32_t triangles)
{
	memset(edges, 0, sizeof *edges);
	const size_t most = 3 * (size_t)triangles;
	size_t capacity = 16;
	while (capacity < 2 * most)
		capacity *= 2;
	edges->slots = malloc(capacity * sizeof *edges->slots);
	edges->in_order = malloc(most * sizeof *edges->in_order);
	if (edges->slots == NULL || edges->in_order == NULL)
		return false;
	for (size_t s = 0; s < capacity; s++)
		edges->slots[s].key = UINT64_MAX;
	edges->mask = capacity - 1;
	sm_keyed_hash_draw_key(edges->key);
	return true;
}

mesh_edge* sm_mesh_edges_find(mesh_edges* edges, int32_t a, int32_t b)
{
	const uint32_t low = (uint32_t)(a < b ? a : b), high = (uint32_t)(a < b ? b : a);
	const uint64_t key = ((uint64_t)low << 32) | high;
	uint64_t s = sm_keyed_hash_word(edges->key, key) & edges->mask;
	edges->probes++;
	while (edges->slots[s].key != UINT64_MAX && edges->slots[s].key != key) {
		s = (s + 1) & edges->mask;
		edges->probes++;
	}
	mesh_edge* e = &edges->slots[s];
	if (e->key == UINT64_MAX) {
		e->key = key;
		e->triangles = 0;
		e->area = 0.0;
		edges->in_order[edges->count++] = (int32_t)s;
	}
	return e;
}

const mesh_edge* sm_mesh_edges_at(const mesh_edges* edges, int32_t k)
{
	return &edges->slots[edges->in_order[k]];
}

void sm_mesh_edges_free(mesh_edges* edges)
{
	if (edges == NULL)
		return;
	free(edges->slots);
	free(edges->in_order);
	memset(edges, 0, sizeof *edges);
}

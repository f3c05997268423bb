// The edges of a triangle mesh (see mesh_edges.h).
#include "mesh_edges.h"

#include "keyed_hash.h"

#include <stdlib.h>
#include <string.h>

enum { FIRST_SLOTS = 16 };

static uint64_t edge_key(int32_t a, int32_t b)
{
	const uint32_t low = (uint32_t)(a < b ? a : b), high = (uint32_t)(a < b ? b : a);
	return ((uint64_t)low << 32) | high;
}

// The slot holding `key`, or the empty slot where it belongs.
static uint64_t slot_of(mesh_edges* edges, uint64_t key)
{
	uint64_t s = sm_keyed_hash_word(edges->key, key) & edges->mask;
	edges->probes++;
	while (edges->slots[s].key != UINT64_MAX && edges->slots[s].key != key) {
		s = (s + 1) & edges->mask;
		edges->probes++;
	}
	return s;
}

// Room for `capacity` slots (a power of two) and half as many edges, the entries moved in their
// order of appearance. False, with the table unchanged, when memory runs out.
static bool resize(mesh_edges* edges, size_t capacity)
{
	mesh_edge* slots = malloc(capacity * sizeof *slots);
	int32_t* in_order = realloc(edges->in_order, capacity / 2 * sizeof *in_order);
	if (in_order != NULL)
		edges->in_order = in_order;
	if (slots == NULL || in_order == NULL) {
		free(slots);
		return false;
	}
	for (size_t s = 0; s < capacity; s++)
		slots[s].key = UINT64_MAX;
	mesh_edge* old = edges->slots;
	edges->slots = slots;
	edges->mask = capacity - 1;
	for (int32_t k = 0; k < edges->count; k++) {
		const mesh_edge entry = old[edges->in_order[k]];
		const uint64_t s = slot_of(edges, entry.key);
		edges->slots[s] = entry;
		edges->in_order[k] = (int32_t)s;
	}
	free(old);
	return true;
}

bool sm_mesh_edges_init(mesh_edges* edges)
{
	memset(edges, 0, sizeof *edges);
	sm_keyed_hash_draw_key(edges->key);
	return resize(edges, FIRST_SLOTS);
}

mesh_edge* sm_mesh_edges_find(mesh_edges* edges, int32_t a, int32_t b)
{
	const uint64_t key = edge_key(a, b);
	uint64_t s = slot_of(edges, key);
	if (edges->slots[s].key == key)
		return &edges->slots[s];
	// A new edge; at most half the slots full, so that a lookup stays short.
	if (2 * ((size_t)edges->count + 1) > edges->mask + 1) {
		if (!resize(edges, 2 * (edges->mask + 1)))
			return NULL;
		s = slot_of(edges, key);
	}
	mesh_edge* e = &edges->slots[s];
	e->key = key;
	e->triangles = 0;
	e->area = 0.0;
	edges->in_order[edges->count++] = (int32_t)s;
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

// The edges of a triangle mesh, found by their two vertices: an open-addressing hash table
// (linear probing, at most half full) keyed by the sorted vertex pair. Each entry remembers how
// many triangles share the edge and the vertex opposite it in the first two, which are the ends
// of the bending spring across an interior edge.
//
// The vertex numbers come from files that may be hostile (an OBJ file's faces): the hash is keyed
// (keyed_hash.h), with a key drawn for each table, so that a file cannot choose faces whose edges
// fall into one run of slots and make every lookup walk it.
#pragma once

#include <stdbool.h>
#include <stdint.h>

typedef struct mesh_edge {
	uint64_t key;         // (low vertex << 32) | high vertex, or UINT64_MAX when empty
	int32_t triangles;    // triangles sharing the edge
	int32_t opposite[2];  // the vertex opposite the edge in the first two triangles
	double area;          // of the triangles sharing the edge [m^2]
} mesh_edge;

typedef struct mesh_edges {
	mesh_edge* slots;
	uint64_t mask;      // slots - 1, the slots a power of two
	int32_t* in_order;  // slot of each edge in order of first appearance
	int32_t count;      // edges found
	uint64_t key[2];    // the hash's key
	int64_t probes;     // slots looked at by every sm_mesh_edges_find so far, growing included
} mesh_edges;

// An empty table. It grows as edges are found, so that its memory follows the edges a mesh has
// (about 1.5 per triangle for a closed surface), not the triangles a file announces before one of
// them is refused. False when memory runs out; sm_mesh_edges_free frees what it holds either way.
bool sm_mesh_edges_init(mesh_edges* edges);

// The edge between vertices a and b (a != b, both >= 0): found, or entered with no triangles and
// no area if it is new (at most INT32_MAX edges). The entry stays where it is until the next call,
// which may move the table. NULL when the table had to grow and memory ran out (the table is then
// unchanged).
mesh_edge* sm_mesh_edges_find(mesh_edges* edges, int32_t a, int32_t b);

// The k-th edge found, in order of first appearance (0 <= k < edges->count).
const mesh_edge* sm_mesh_edges_at(const mesh_edges* edges, int32_t k);

// Frees what the table holds; accepts NULL.
void sm_mesh_edges_free(mesh_edges* edges);

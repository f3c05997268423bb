// An index from names to numbers (a parameter's, a particle's, a structure's or a port's), for the
// model-file loader: lookups and insertions in constant expected time, so that loading a file
// with n names and n references to them takes time proportional to n.
//
// The index keeps no names of its own: it stores each number with 32 bits of its name's hash
// and asks its owner for the name (name_of) when it has to compare. Names are byte strings
// without NUL bytes, given with their length, so that a lookup can use part of a longer string
// (the `cloth` of `cloth[3,4]`).
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// The name stored under `value`, NUL-terminated; owner is what sm_name_index_init was given.
typedef const char* (*name_index_name_fn)(const void* owner, int32_t value);

typedef struct name_slot {
	uint32_t tag;   // the upper 32 bits of the name's hash; tag & (size - 1) is its home slot
	int32_t value;  // -1: empty
} name_slot;

typedef struct name_index {
	name_slot* slots;
	int64_t size;     // slots, a power of two (0 until the first insertion)
	int64_t count;    // names held; at most half the slots
	uint64_t key[2];  // the hash's key, drawn at the first insertion
	name_index_name_fn name_of;
	const void* owner;
} name_index;

// An empty index whose names owner's name_of gives. Allocates nothing.
void sm_name_index_init(name_index* index, name_index_name_fn name_of, const void* owner);

// The value stored under name[0, length), or -1.
int32_t sm_name_index_find(const name_index* index, const char* name, size_t length);

// Stores value (>= 0) under name[0, length) unless the name is there already. *holder gets -1
// if the value was stored, or the value already stored under the name (nothing changes).
// Returns false only when memory runs out (the index is unchanged and still usable).
bool sm_name_index_insert(name_index* index, const char* name, size_t length, int32_t value, int32_t* holder);

// Frees the slots; the index is then empty (and may be used again). Accepts NULL.
void sm_name_index_free(name_index* index);

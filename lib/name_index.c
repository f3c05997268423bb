// An index from names to numbers: open addressing with linear probing, at most half full.
//
// Names come from model files, which may be hostile: the hash is keyed (keyed_hash.h), with a key
// drawn for each index at its first insertion, so that a file cannot make its names fall into one
// run of slots.
#include "name_index.h"

#include "keyed_hash.h"

#include <stdlib.h>
#include <string.h>

void sm_name_index_init(name_index* index, name_index_name_fn name_of, const void* owner)
{
	memset(index, 0, sizeof *index);
	index->name_of = name_of;
	index->owner = owner;
}

static uint32_t tag_of(const name_index* index, const char* name, size_t length)
{
	return (uint32_t)(sm_keyed_hash_bytes(index->key, (const unsigned char*)name, length) >> 32);
}

// The slot holding name (tag `tag`), or the empty slot where it would go.
static int64_t slot_of(const name_index* index, const char* name, size_t length, uint32_t tag)
{
	const uint64_t mask = (uint64_t)index->size - 1;
	for (uint64_t s = tag & mask;; s = (s + 1) & mask) {
		const name_slot* slot = &index->slots[s];
		if (slot->value < 0)
			return (int64_t)s;
		if (slot->tag == tag) {
			const char* stored = index->name_of(index->owner, slot->value);
			if (strncmp(stored, name, length) == 0 && stored[length] == '\0')
				return (int64_t)s;
		}
	}
}

int32_t sm_name_index_find(const name_index* index, const char* name, size_t length)
{
	if (index->count == 0)
		return -1;
	return index->slots[slot_of(index, name, length, tag_of(index, name, length))].value;
}

// Twice the slots (64 at first), every name moved to its place among them by its tag.
static bool grow(name_index* index)
{
	const int64_t size = index->size > 0 ? 2 * index->size : 64;
	name_slot* slots = malloc((size_t)size * sizeof *slots);
	if (slots == NULL)
		return false;
	for (int64_t s = 0; s < size; s++)
		slots[s].value = -1;
	const uint64_t mask = (uint64_t)size - 1;
	for (int64_t s = 0; s < index->size; s++) {
		const name_slot slot = index->slots[s];
		if (slot.value < 0)
			continue;
		uint64_t t = slot.tag & mask;
		while (slots[t].value >= 0)
			t = (t + 1) & mask;
		slots[t] = slot;
	}
	if (index->size == 0)
		sm_keyed_hash_draw_key(index->key);
	free(index->slots);
	index->slots = slots;
	index->size = size;
	return true;
}

bool sm_name_index_insert(name_index* index, const char* name, size_t length, int32_t value, int32_t* holder)
{
	*holder = sm_name_index_find(index, name, length);
	if (*holder >= 0)
		return true;
	if (2 * (index->count + 1) > index->size && !grow(index))
		return false;
	const uint32_t tag = tag_of(index, name, length);
	name_slot* slot = &index->slots[slot_of(index, name, length, tag)];
	slot->tag = tag;
	slot->value = value;
	index->count++;
	return true;
}

void sm_name_index_free(name_index* index)
{
	if (index == NULL)
		return;
	free(index->slots);
	index->slots = NULL;
	index->size = index->count = 0;
}

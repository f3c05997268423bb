// An index from names to numbers: open addressing with linear probing, at most half full.
//
// Names come from model files, which may be hostile. With a fixed hash function a file can be
// made of names that all fall into one run of slots (finding them takes a few hours of
// computing, once), and every lookup then walks the run: loading becomes quadratic again. The
// hash is therefore SipHash-1-3 (Aumasson and Bernstein, "SipHash: a fast short-input PRF",
// 2012; the variant Rust's HashMap uses for the same reason) with a key drawn for each index from
// the operating system's random source, which a file cannot know in advance. The key changes
// where names sit, never what a lookup finds, so loading gives the same results every time.
#define _DEFAULT_SOURCE  // getentropy

#include "name_index.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static uint64_t rotate(uint64_t x, int bits)
{
	return (x << bits) | (x >> (64 - bits));
}

// One SipRound of the state v.
static void sip_round(uint64_t v[4])
{
	v[0] += v[1];
	v[1] = rotate(v[1], 13) ^ v[0];
	v[0] = rotate(v[0], 32);
	v[2] += v[3];
	v[3] = rotate(v[3], 16) ^ v[2];
	v[0] += v[3];
	v[3] = rotate(v[3], 21) ^ v[0];
	v[2] += v[1];
	v[1] = rotate(v[1], 17) ^ v[2];
	v[2] = rotate(v[2], 32);
}

// SipHash-1-3 of data[0, length): one round per 8-byte word, three to finish. The last word
// holds the remaining bytes and, in its top byte, the length mod 256 (little-endian words).
static uint64_t siphash13(const uint64_t key[2], const unsigned char* data, size_t length)
{
	uint64_t v[4] = {0x736f6d6570736575ULL ^ key[0], 0x646f72616e646f6dULL ^ key[1],
	                 0x6c7967656e657261ULL ^ key[0], 0x7465646279746573ULL ^ key[1]};
	const size_t whole = length - length % 8;
	for (size_t at = 0; at <= whole; at += 8) {
		const size_t bytes = at < whole ? 8 : length - whole;
		uint64_t word = at < whole ? 0 : (uint64_t)length << 56;
		for (size_t b = 0; b < bytes; b++)
			word |= (uint64_t)data[at + b] << (8 * b);
		v[3] ^= word;
		sip_round(v);
		v[0] ^= word;
	}
	v[2] ^= 0xff;
	for (int r = 0; r < 3; r++)
		sip_round(v);
	return v[0] ^ v[1] ^ v[2] ^ v[3];
}

// A key nobody can predict: getentropy, or where that fails (a sandbox without the system
// call) the addresses the system randomises and the clock.
static void draw_key(name_index* index)
{
	if (getentropy(index->key, sizeof index->key) == 0)
		return;
	int local = 0;
	index->key[0] = (uint64_t)(uintptr_t)index ^ ((uint64_t)(uintptr_t)&local << 17) ^ (uint64_t)time(NULL);
	index->key[1] = (uint64_t)(uintptr_t)&draw_key ^ ((uint64_t)clock() << 29) ^ 0x9e3779b97f4a7c15ULL;
}

void sm_name_index_init(name_index* index, name_index_name_fn name_of, const void* owner)
{
	memset(index, 0, sizeof *index);
	index->name_of = name_of;
	index->owner = owner;
}

static uint32_t tag_of(const name_index* index, const char* name, size_t length)
{
	return (uint32_t)(siphash13(index->key, (const unsigned char*)name, length) >> 32);
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
		draw_key(index);
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

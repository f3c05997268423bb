// SipHash-1-3 (Aumasson and Bernstein, "SipHash: a fast short-input PRF", 2012; the variant Rust's
// HashMap uses for the same reason) with a key drawn from the operating system's random source.
//
// With a fixed hash function a file can be made of keys that all fall into one run of slots of an
// open-addressing table (finding them takes minutes to hours of computing, once), and every lookup
// then walks the run: loading becomes quadratic. A key drawn for each table, which a file cannot
// know in advance, changes where keys sit, never what a lookup finds, so loading gives the same
// results every time.
#define _DEFAULT_SOURCE  // getentropy

#include "keyed_hash.h"

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

static void start(const uint64_t key[2], uint64_t v[4])
{
	v[0] = 0x736f6d6570736575ULL ^ key[0];
	v[1] = 0x646f72616e646f6dULL ^ key[1];
	v[2] = 0x6c7967656e657261ULL ^ key[0];
	v[3] = 0x7465646279746573ULL ^ key[1];
}

// One compression round of a message word.
static void compress(uint64_t v[4], uint64_t word)
{
	v[3] ^= word;
	sip_round(v);
	v[0] ^= word;
}

// Three rounds to finish.
static uint64_t finish(uint64_t v[4])
{
	v[2] ^= 0xff;
	for (int r = 0; r < 3; r++)
		sip_round(v);
	return v[0] ^ v[1] ^ v[2] ^ v[3];
}

void sm_keyed_hash_draw_key(uint64_t key[2])
{
	if (getentropy(key, 2 * sizeof key[0]) == 0)
		return;
	int local = 0;
	key[0] = (uint64_t)(uintptr_t)key ^ ((uint64_t)(uintptr_t)&local << 17) ^ (uint64_t)time(NULL);
	key[1] = (uint64_t)(uintptr_t)&sm_keyed_hash_draw_key ^ ((uint64_t)clock() << 29) ^ 0x9e3779b97f4a7c15ULL;
}

// One round per 8-byte word, three to finish. The last word holds the remaining bytes and, in its
// top byte, the length mod 256 (little-endian words).
uint64_t sm_keyed_hash_bytes(const uint64_t key[2], const unsigned char* data, size_t length)
{
	uint64_t v[4];
	start(key, v);
	const size_t whole = length - length % 8;
	for (size_t at = 0; at <= whole; at += 8) {
		const size_t bytes = at < whole ? 8 : length - whole;
		uint64_t word = at < whole ? 0 : (uint64_t)length << 56;
		for (size_t b = 0; b < bytes; b++)
			word |= (uint64_t)data[at + b] << (8 * b);
		compress(v, word);
	}
	return finish(v);
}

uint64_t sm_keyed_hash_word(const uint64_t key[2], uint64_t value)
{
	uint64_t v[4];
	start(key, v);
	compress(v, value);
	compress(v, (uint64_t)8 << 56);  // no bytes left, the length 8
	return finish(v);
}

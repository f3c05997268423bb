// A keyed hash for hash tables whose keys come from files that may be hostile (names in a model
// file, vertex pairs of an OBJ mesh): SipHash-1-3 with a key drawn from the operating system's
// random source for each table. A file cannot know the key, so it cannot choose keys that fall
// into one run of slots and make every lookup walk it.
#pragma once

#include <stddef.h>
#include <stdint.h>

// A key nobody can predict: getentropy, or where that fails (a sandbox without the system call)
// the addresses the system randomises and the clock.
void sm_keyed_hash_draw_key(uint64_t key[2]);

// SipHash-1-3 of data[0, length) under key.
uint64_t sm_keyed_hash_bytes(const uint64_t key[2], const unsigned char* data, size_t length);

// SipHash-1-3 of the 8 bytes of value, least significant first, under key: what
// sm_keyed_hash_bytes gives for them, whatever the machine's byte order.
uint64_t sm_keyed_hash_word(const uint64_t key[2], uint64_t value);

/* An item's slot in an agent's segment and its sequence lock: a writer takes
 * the slot (its sequence even -> odd), stores the value's words and gives it
 * back (odd -> even, with the value's time); a reader copies the words and
 * tries again when the sequence moved meanwhile. Private to librtdb (rtdb.c). */
#ifndef CANHIL_RTDB_SLOT_H
#define CANHIL_RTDB_SLOT_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
  _Atomic uint32_t seq; /* odd while a write is in progress */
  uint32_t size;
  int64_t stamp_ns; /* CLOCK_MONOTONIC time the value describes */
} slot_header;

/* The payload moves in relaxed atomic 8-byte words (slots are 8-aligned and
 * padded to whole words): a reader racing a writer is the sequence lock's
 * normal case, and with plain memcpy that race is undefined behaviour (and
 * what ThreadSanitizer reports). On x86-64 these are ordinary moves. A whole
 * value has loops of its own (store_words, load_words): whole words the
 * compiler can move in bulk, 3 to 5 times faster for VISION_INFO's 4.8 kB
 * than the range loops below, which serve any part. */
static inline void store_words(slot_header* s, const void* value) {
  uint64_t* dst = (uint64_t*)(void*)(s + 1);
  const char* src = (const char*)value;
  const uint32_t size = s->size;
  uint32_t i = 0;
  for (; i + 8 <= size; i += 8) {
    uint64_t w;
    memcpy(&w, src + i, 8);
    __atomic_store_n(dst + i / 8, w, __ATOMIC_RELAXED);
  }
  if (i < size) {
    uint64_t w = 0;
    memcpy(&w, src + i, size - i);
    __atomic_store_n(dst + i / 8, w, __ATOMIC_RELAXED);
  }
}

static inline void load_words(const slot_header* s, void* value) {
  const uint64_t* src = (const uint64_t*)(const void*)(s + 1);
  char* dst = (char*)value;
  const uint32_t size = s->size;
  uint32_t i = 0;
  for (; i + 8 <= size; i += 8) {
    const uint64_t w = __atomic_load_n(src + i / 8, __ATOMIC_RELAXED);
    memcpy(dst + i, &w, 8);
  }
  if (i < size) {
    const uint64_t w = __atomic_load_n(src + i / 8, __ATOMIC_RELAXED);
    memcpy(dst + i, &w, size - i);
  }
}

/* Bytes [offset, offset + size) of the slot's value, by the words that hold them. */
static inline void load_range(const slot_header* s, size_t offset, size_t size, void* value) {
  const uint64_t* src = (const uint64_t*)(const void*)(s + 1);
  char* dst = (char*)value;
  size_t at = offset;
  const size_t end = offset + size;
  while (at < end) {
    const uint64_t w = __atomic_load_n(src + at / 8, __ATOMIC_RELAXED);
    const size_t from = at % 8;
    const size_t n = (8 - from < end - at) ? 8 - from : end - at;
    memcpy(dst + (at - offset), (const char*)&w + from, n);
    at += n;
  }
}

/* The words of the slot's value that hold bytes [offset, offset + size), from
 * the whole image `value` (bytes past the item's end in its last word: zero,
 * as store_words leaves them). */
static inline void store_word_range(slot_header* s, const void* value, size_t offset, size_t size) {
  uint64_t* dst = (uint64_t*)(void*)(s + 1);
  const char* src = (const char*)value;
  const size_t end = offset + size;
  if (size == 0) return;
  for (size_t i = offset - offset % 8; i < end; i += 8) {
    uint64_t w = 0;
    memcpy(&w, src + i, i + 8 <= s->size ? 8 : s->size - i);
    __atomic_store_n(dst + i / 8, w, __ATOMIC_RELAXED);
  }
}

/* Takes the slot (even -> odd: one writer at a time); returns the even sequence it had. */
static inline uint32_t take_slot(slot_header* s) {
  uint32_t seq = atomic_load_explicit(&s->seq, memory_order_relaxed);
  for (;;) {
    if ((seq & 1u) == 0 &&
        atomic_compare_exchange_weak_explicit(&s->seq, &seq, seq + 1, memory_order_acquire, memory_order_relaxed)) {
      break;
    }
    seq = atomic_load_explicit(&s->seq, memory_order_relaxed);
  }
  atomic_thread_fence(memory_order_release);
  return seq;
}

static inline void release_slot(slot_header* s, uint32_t seq, int64_t stamp) {
  __atomic_store_n(&s->stamp_ns, stamp, __ATOMIC_RELAXED);
  atomic_store_explicit(&s->seq, seq + 2, memory_order_release);
}

static inline void write_slot(slot_header* s, const void* value, int64_t stamp) {
  const uint32_t seq = take_slot(s);
  store_words(s, value);
  release_slot(s, seq, stamp);
}

/* The whole value (size = s->size, offset 0) or a part of it, copied whole
 * from one write; returns the time that write gave it. */
static inline int64_t read_slot_stamped(const slot_header* s, size_t offset, size_t size, void* value) {
  for (;;) {
    const uint32_t before = atomic_load_explicit(&s->seq, memory_order_acquire);
    if (before & 1u) continue;
    if (offset == 0 && size == s->size) {
      load_words(s, value);
    } else {
      load_range(s, offset, size, value);
    }
    const int64_t stamp = __atomic_load_n(&s->stamp_ns, __ATOMIC_RELAXED);
    atomic_thread_fence(memory_order_acquire);
    if (atomic_load_explicit(&s->seq, memory_order_relaxed) == before) return stamp;
  }
}

#endif

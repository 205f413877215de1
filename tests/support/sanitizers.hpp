// CANHIL_UNDER_TSAN: 1 when this test program is built with ThreadSanitizer
// (g++ defines __SANITIZE_THREAD__, clang answers __has_feature), else 0.
// Tests that race on purpose, or that replace what TSan's runtime defines,
// are left out under it; the plain and ASan flavours run them.
#pragma once

#if defined(__SANITIZE_THREAD__)
#define CANHIL_UNDER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CANHIL_UNDER_TSAN 1
#endif
#endif
#ifndef CANHIL_UNDER_TSAN
#define CANHIL_UNDER_TSAN 0
#endif

/* The frame signal: one named POSIX semaphore per memory space, which the
 * vision's writer posts (DB_signal_frame) and the space's agent waits on
 * (DB_wait_frame). A process keeps open the semaphores of the spaces it has;
 * rtdb.c names them and removes one when the last process leaves its space. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): the POSIX/GNU feature macro
#include <errno.h>
#include <fcntl.h>
#include <semaphore.h>
#include <stdatomic.h>
#include <stddef.h>
#include <time.h>

#include "rtdb_internal.h"

/* The kept semaphores, by memory space (either set's agents): opened at a
 * space's first signal or wait, closed when the process leaves it. */
static sem_t* _Atomic g_kept[CANHIL_RTDB_SPACES];

static sem_t* open_frames(int space, canhil_rtdb_frames_name name_of) {
  char name[64];
  name_of(space, name, sizeof name);
  sem_t* s = sem_open(name, O_CREAT, 0600, 0);
  return s == SEM_FAILED ? NULL : s;
}

/* Space `space`'s semaphore, opened once; another thread's, when it kept its first. */
static sem_t* kept(int space, canhil_rtdb_frames_name name_of) {
  sem_t* s = atomic_load(&g_kept[space]);
  if (s != NULL) return s;
  s = open_frames(space, name_of);
  if (s == NULL) return NULL;
  sem_t* none = NULL;
  if (!atomic_compare_exchange_strong(&g_kept[space], &none, s)) {
    sem_close(s);
    s = none;
  }
  return s;
}

void canhil_rtdb_frames_forget(int space) {
  sem_t* s = atomic_exchange(&g_kept[space], NULL);
  if (s != NULL) sem_close(s);
}

int canhil_rtdb_frames_post(int space, canhil_rtdb_frames_name name_of, int keep) {
  sem_t* s = keep ? kept(space, name_of) : open_frames(space, name_of);
  if (s == NULL) return -1;
  int value = 0;
  if (sem_getvalue(s, &value) == 0 && value == 0) sem_post(s);
  if (!keep) sem_close(s);
  return 0;
}

int canhil_rtdb_frames_wait(int space, canhil_rtdb_frames_name name_of, int timeout_ms) {
  sem_t* const frames = kept(space, name_of);
  if (frames == NULL) return -1;
  int r;
  if (timeout_ms < 0) {
    do {
      r = sem_wait(frames);
    } while (r < 0 && errno == EINTR);
  } else {
    struct timespec deadline;
    clock_gettime(CLOCK_REALTIME, &deadline);
    deadline.tv_sec += timeout_ms / 1000;
    deadline.tv_nsec += (long)(timeout_ms % 1000) * 1000000L;
    if (deadline.tv_nsec >= 1000000000L) {
      deadline.tv_sec += 1;
      deadline.tv_nsec -= 1000000000L;
    }
    do {
      r = sem_timedwait(frames, &deadline);
    } while (r < 0 && errno == EINTR);
    if (r < 0 && errno == ETIMEDOUT) return 1;
  }
  if (r < 0) return -1;
  while (sem_trywait(frames) == 0) {
  } /* several posts wake once */
  return 0;
}

/* pmandefs.h — the System V keys of a CAMBADA robot's process manager (PMan),
 * as a CAMBADA client expects them (canhil's own header, CAMBADA's names).
 *
 * The omni-vision master of robot N and its clients meet at key
 * SHMEM_OCAM_PMAN_KEY + 2*N, used for both the shared-memory table and the
 * one-semaphore set: PMAN_init() adds 2*AGENT to both keys (see pman.h). */
#ifndef PMANDEFS_H_INCLUDED
#define PMANDEFS_H_INCLUDED

#define SHMEM_FCAM_PMAN_KEY 0x9010 /* table key of the front-camera master */
#define SHMEM_OCAM_PMAN_KEY 0x9011 /* table key of the omni-camera master (the robot's master) */
#define SEM_FCAM_PMAN_KEY 0x9010   /* semaphore key of the front-camera master */
#define SEM_OCAM_PMAN_KEY 0x9011   /* semaphore key of the omni-camera master */

#endif

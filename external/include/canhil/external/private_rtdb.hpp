// canhil/external/private_rtdb.hpp — the RTDB keys of a canhil process that plays its own
// robots (a run in virtual time, a match and its workers, a benchmark): keys
// of this process, so that it never meets a live robot's database nor another
// such process's, and the leftovers of earlier such processes removed. A
// canhil killed outright (SIGKILL, a crash) cannot remove its shared memory;
// the next one does, for its own kind of key.
#pragma once

namespace canhil::external {

/// The first byte of the keys canhil's runs and matches use, and of the benchmark's.
inline constexpr unsigned kRunKeyPrefix = 0x58;
inline constexpr unsigned kBenchKeyPrefix = 0x57;

/// Removes the shared memory segments whose key starts with `prefix`, of this
/// user, that no process is attached to and whose creator has ended; then,
/// unless the user set RTDB_KEY, sets it to a range of 256 keys of its own:
/// `prefix` << 24 plus this process's id << 8 (the id's low 16 bits), or the
/// next range no segment is in when another process holds that one (their
/// ids share the low bits). The range is claimed from the moment it is
/// chosen (a segment on its last key, which the RTDB leaves free), so that two
/// processes starting together never choose one range. Returns how many
/// segments it removed.
int use_private_rtdb_keys(unsigned prefix);

/// In a match's worker process (`worker` from 0): its own range, chosen as
/// use_private_rtdb_keys() chose the batch's, when canhil chose that; when the
/// user set RTDB_KEY, the user's key plus (worker + 1) << 16.
void use_worker_rtdb_keys(int worker);

/// Gives back the range this process claimed (main() at the end of every
/// command, a worker before it ends), when it is still in the IPC namespace
/// it claimed it in. A process killed outright leaves its claim, an orphan
/// that the next one removes.
void release_private_rtdb_keys();

/// Removes the segments use_private_rtdb_keys() would remove as orphans (a
/// batch's, after its workers ended in IPC namespaces of their own and could
/// not give their claims back); returns how many.
int remove_orphan_rtdb_keys(unsigned prefix);

}  // namespace canhil::external

// app/private_rtdb.hpp — the RTDB keys of a canhil process that plays its own
// robots (a run in virtual time, a match, a benchmark): keys of this process,
// so that it never meets a live robot's database, and the leftovers of
// earlier such processes removed. A canhil killed outright (SIGKILL, a crash)
// cannot remove its shared memory; the next one does, for its own kind of key.
#pragma once

namespace canhil::app {

/// The first byte of the keys canhil's runs and matches use (a match's worker
/// adds its number << 16), and of the benchmark's.
inline constexpr unsigned kRunKeyPrefix = 0x58;
inline constexpr unsigned kBenchKeyPrefix = 0x57;

/// Removes the shared memory segments whose key starts with `prefix`, of this
/// user, that no process is attached to and whose creator has ended; then,
/// unless the user set RTDB_KEY, sets it to `prefix` << 24 plus this
/// process's id << 8. Returns how many segments it removed.
int use_private_rtdb_keys(unsigned prefix);

}  // namespace canhil::app

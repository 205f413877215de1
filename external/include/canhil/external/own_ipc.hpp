// canhil/external/own_ipc.hpp — a System V IPC namespace of one's own, for a
// process that runs a team's processes beside another that runs the same
// team's: a team's RTDB and PMan take fixed keys (its rtdb.conf, its agent
// number), so two matches on one machine would meet in the same segments and
// semaphores. Everything the process creates after entering, and everything its
// children create, is seen by them alone, and goes when the last of them ends.
#pragma once

namespace canhil::external {

/// How the namespace is made: by the process itself (needs CAP_SYS_ADMIN, as
/// root has), or inside a user namespace of its own that maps the process's
/// user and group to themselves (any user, where the kernel allows
/// unprivileged user namespaces, as Debian's does).
enum class IpcWay { kDirect, kUserNamespace };

/// Enters a new IPC namespace: directly when allowed, else through a user
/// namespace (or `way`, to choose). The calling process must have one thread
/// for the second way (a freshly forked child; not under ThreadSanitizer,
/// whose runtime keeps a thread of its own). Throws SetupError saying what failed and what to
/// do. Returns the way taken.
IpcWay enter_own_ipc_namespace();
void enter_own_ipc_namespace(IpcWay way);

}  // namespace canhil::external

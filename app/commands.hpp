// app/commands.hpp — canhil's subcommands. Each returns the process exit status.
#pragma once

#include <optional>
#include <string>

#include "args.hpp"

namespace canhil::app {

/// `canhil frames list|encode|decode ...`; args still hold the leading "frames".
int run_frames(Args& args, const std::optional<std::string>& dbc);
/// `canhil dump IFACE` or `canhil dump --log FILE`.
int run_dump(Args& args, const std::optional<std::string>& dbc);
/// `canhil experiment NAME [options]`: a physics calibration experiment.
int run_experiment(Args& args);
/// `canhil run --virtual-time ...`: the whole loop in virtual time.
int run_run(Args& args, const std::optional<std::string>& dbc);
/// `canhil bench`: the five-robot real-time factor in virtual time.
int run_bench(Args& args, const std::optional<std::string>& dbc);
/// `canhil timing SOURCE`: timing and FTT compliance of a log or interface.
int run_timing(Args& args, const std::optional<std::string>& dbc);
/// `canhil timing --analyse [TRACE]`: schedulability of the message set, and a trace against its bounds.
int run_timing_analyse(Args& args, const std::optional<std::string>& dbc);
/// `canhil rtdb list|dump ITEM|watch ITEM|replicate`.
int run_rtdb(Args& args);
/// `canhil nodes --iface IFACE`: one robot's node set with physics, in real time.
int run_nodes(Args& args, const std::optional<std::string>& dbc);
/// `canhil coach STATE|status|--robot N ...`: the base station's orders to a running run.
int run_coach(Args& args, const std::optional<std::string>& dbc);
/// `canhil match SCENARIO`: whole matches of two teams in virtual time.
int run_match(Args& args, const std::optional<std::string>& dbc);
/// `canhil test FILES...`: test files run and judged (verdict/).
int run_test(Args& args, const std::optional<std::string>& dbc);
int run_view(Args& args, const std::optional<std::string>& dbc);
int run_play(Args& args, const std::optional<std::string>& dbc);
/// `canhil pman list`: every robot's PMan table, its processes and their activations.
int run_pman(Args& args);
/// `canhil bus up|exec|list|down|link|preload`: the user-space CAN bus.
int run_bus(Args& args, const std::optional<std::string>& dbc);

}  // namespace canhil::app

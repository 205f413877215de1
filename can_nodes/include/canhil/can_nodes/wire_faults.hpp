// canhil/can_nodes/wire_faults.hpp — the fault language's rules that act on
// a timed wire (fault.hpp: ber, noack, stuck, babble, cut, busoff, and error)
// as the wire's own rules (wire::FaultRule) for one robot's bus.
#pragma once

#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/wire/wire_fault.hpp"

namespace canhil::can_nodes {

/// The controller of a node named as rules name them (fault_node_name; `laptop`
/// for the team's handler), or nothing when that node is not on this bus.
using ControllerOf = std::function<std::optional<wire::ControllerId>(std::string_view node)>;

/// The wire's rules for `rules` that act on a timed wire (wire_only, and
/// `error`): a message target by its identifier, a node by its controller,
/// times from the run's start. A rule whose node is not on this bus (a node
/// left to a real board) gives none.
std::vector<wire::FaultRule> wire_rules(const std::vector<FaultRule>& rules, const frames::MessageSet& set,
                                        const ControllerOf& controller_of);

}  // namespace canhil::can_nodes

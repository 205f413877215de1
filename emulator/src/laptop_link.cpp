#include "canhil/emulator/laptop_link.hpp"

#include <cstdio>
#include <sstream>

#include "canhil/base/setup_error.hpp"

namespace canhil::emulator {

LaptopSide resolve_laptop(LaptopSide side, std::size_t robots, bool realtime) {
  if (side.rtdb_lib.empty()) side.rtdb_lib = "builtin";
  const bool builtin = side.rtdb_lib == "builtin";
  if (builtin && (!side.rtdb_items.empty() || !side.rtdb_ini.empty())) {
    throw SetupError(
        "rtdb_items and rtdb_ini describe a team RTDB library's table; give that library too (rtdb_lib, --rtdb-lib), "
        "or leave them out for canhil's linked RTDB, which has its own table");
  }
  if (!builtin && (side.rtdb_items.empty() || side.rtdb_ini.empty())) {
    throw SetupError("the team RTDB library " + side.rtdb_lib +
                     " needs its item table: give the team's generated rtdb_user.h (rtdb_items, --rtdb-items) and "
                     "its rtdb.ini (rtdb_ini, --rtdb-ini)");
  }
  if (side.layout.empty()) side.layout = builtin ? "canhil" : "cambada";
  if (side.pman.empty()) side.pman = realtime ? "builtin" : "none";
  if (!side.replicate) side.replicate = robots > 1;
  return side;
}

rtdb::Layout load_layout(const std::string& name) {
  for (const std::string_view shipped : rtdb::Layout::shipped_names()) {
    if (name == shipped) return rtdb::Layout::shipped(name);
  }
  return rtdb::Layout::load(name);
}

bool layout_tells_attacks(const rtdb::Layout& layout) {
  const rtdb::ItemLayout* coach = layout.item("COACH_INFO");
  return coach != nullptr && coach->has("attacks");
}

namespace {

std::unique_ptr<rtdb::Database> open_database(const LaptopSide& side, int set) {
  if (side.rtdb_lib == "builtin") return rtdb::open_builtin(rtdb::Scope::kAllAgents, set);
  return rtdb::open_library(side.rtdb_lib, rtdb::ItemTable::from_files(side.rtdb_items, side.rtdb_ini),
                            rtdb::Scope::kAllAgents, std::filesystem::path(side.rtdb_ini), set);
}

std::unique_ptr<pman::Masters> open_masters(const std::string& pman, int rtdb_set) {
  if (pman == "none") return nullptr;
  if (pman == "builtin") return pman::builtin_masters(rtdb_set);
  return pman::library_masters(pman);
}

}  // namespace

// One robot's items, resolved and checked once.
struct LaptopLink::Robot {
  int agent = 0;
  int vision_id = -1;
  std::unique_ptr<rtdb::ItemBuffer> vision;
  bool vision_put = false;  // the slot holds the buffer's last image: later frames put only what changed
  rtdb::Quantity lines, obstacles, balls;
  int pos_id = -1;
  std::unique_ptr<rtdb::ItemBuffer> pos;
  rtdb::Quantity pos_x, pos_y, pos_heading;
  int setpose_id = -1;  // resolved at the first place()
  std::unique_ptr<rtdb::ItemBuffer> setpose;
};

LaptopLink::LaptopLink(const LaptopSide& side, const std::vector<int>& agents, const CoachState& coach, int rtdb_set)
    : db_(open_database(side, rtdb_set)),
      layout_(load_layout(side.layout)),
      coach_period_(from_seconds(side.coach_period_s)) {
  const rtdb::ItemLayout& vision = rtdb::require(layout_, "VISION_INFO", {"lines", "obstacles", "balls"});
  const rtdb::ItemLayout* pos = layout_.item("CMD_POS");
  if (pos != nullptr && !(pos->has("x") && pos->has("y") && pos->has("heading"))) pos = nullptr;
  for (const int agent : agents) {
    auto r = std::make_unique<Robot>();
    r->agent = agent;
    r->vision_id = db_->require("VISION_INFO", vision.size_bytes(), agent);
    r->vision = std::make_unique<rtdb::ItemBuffer>(vision);
    r->lines = r->vision->quantity("lines");
    r->obstacles = r->vision->quantity("obstacles");
    r->balls = r->vision->quantity("balls");
    if (pos != nullptr) {
      r->pos_id = db_->require("CMD_POS", pos->size_bytes(), agent);
      r->pos = std::make_unique<rtdb::ItemBuffer>(*pos);
      r->pos_x = r->pos->quantity("x");
      r->pos_y = r->pos->quantity("y");
      r->pos_heading = r->pos->quantity("heading");
    }
    robots_.push_back(std::move(r));
  }
  for (const char* name : {"COACH_INFO", "FORMATION_INFO"}) {
    const rtdb::ItemLayout* item = layout_.item(name);
    if (item == nullptr) continue;  // the team's layout has no such item: its agents do not read it
    CoachItem c;
    c.buffer = std::make_unique<rtdb::ItemBuffer>(*item);
    if (std::string_view(name) == "COACH_INFO") {
      c.game_state = c.buffer->quantity("game_state");
      c.running = c.buffer->quantity("running");
      c.role_auto = c.buffer->quantity("role_auto");
      c.role = c.buffer->quantity("role");
      c.attacks = c.buffer->quantity("attacks");
      c.relocations = c.buffer->quantity("relocations");
    }
    const rtdb::ItemTable& table = db_->items();
    const auto id = table.id(name);
    if (!id) {
      throw SetupError(std::string(name) + ": the layout " + layout_.file() + " describes it but the team's table (" +
                       table.source() +
                       ") has no such item; add it to the team's rtdb.conf or remove it from the "
                       "layout");
    }
    c.id = *id;
    // As the base station's shared item in each robot's database, and as the
    // robot's own (a robot started without a coach reads its own copy).
    const bool base_shares = db_->serves(0) && table.kind(0, c.id) == rtdb::ItemKind::kShared;
    if (base_shares) db_->require(name, item->size_bytes(), 0);
    for (const int agent : agents) {
      if (base_shares) c.targets.emplace_back(agent, 0);
      if (table.kind(agent, c.id) != rtdb::ItemKind::kNone) {
        db_->require(name, item->size_bytes(), agent);
        c.targets.emplace_back(agent, agent);
      }
    }
    if (base_shares) c.targets.emplace_back(0, 0);
    if (c.targets.empty()) {
      throw SetupError(std::string(name) +
                       ": no robot's database has it, neither as the base station's (agent 0) "
                       "shared item nor as its own, in " +
                       table.source() +
                       "; share it from the base station in the team's rtdb.conf, or remove it from the layout");
    }
    coach_items_.push_back(std::move(c));
  }
  if (rtdb_set != 0 && side.pman != "none" && side.pman != "builtin") {
    throw SetupError(
        "the second team's PMan: a team's PMan library (" + side.pman +
        ") puts robot N's table at key 0x9011 + 2 x N for both teams; canhil's own PMan moves the second team's to "
        "0x9111 + 2 x N (its processes started with SECOND_RTDB=1, built against canhil's libpman): give the second "
        "team pman = \"builtin\" or \"none\" in its [teams.laptop]");
  }
  masters_ = open_masters(side.pman, rtdb_set);
  if (masters_) {
    for (const int agent : agents) {
      std::vector<std::string> names;
      for (const std::string& p : side.pman_processes) names.push_back(p + std::to_string(agent));
      masters_->open(agent, names);
    }
  }
  if (side.replicate.value_or(false)) {
    rtdb::ReplicatorConfig cfg;
    cfg.period = from_seconds(side.replicate_period_s);
    replicator_ = std::make_unique<rtdb::Replicator>(*db_, cfg);
  }
  write_coach(coach);
}

LaptopLink::~LaptopLink() {
  if (masters_) masters_->close_all();  // the clients hear of it first (SIGINT), then the RTDB goes
}

void LaptopLink::vision_frame(std::size_t robot, const vision_emu::VisionFrame& frame) {
  Robot& r = *robots_.at(robot);
  rtdb::ItemBuffer& b = *r.vision;  // cleared when made; written only here since
  changed_.clear();
  // A library that takes whole items only (a team's own) needs no ranges.
  std::vector<rtdb::ByteRange>* changed = r.vision_put && db_->puts_ranges() ? &changed_ : nullptr;
  const auto put = [this, &b, changed](rtdb::Quantity q, const std::vector<Eigen::Vector2d>& pts) {
    points_.clear();
    for (const Eigen::Vector2d& p : pts) points_.push_back({p.x(), p.y()});
    b.replace_points(q, points_, changed);
  };
  put(r.obstacles, frame.obstacles);
  put(r.lines, frame.lines);
  put(r.balls, frame.balls);
  // A frame's points fill a quarter of the item or so: the rest is as the
  // last frame left it, in the slot too (this is its only writer).
  if (changed != nullptr) {
    db_->put_ranges(r.agent, r.agent, r.vision_id, b.bytes(), changed_, 0);
  } else {
    db_->put(r.agent, r.agent, r.vision_id, b.bytes(), 0);
    r.vision_put = true;
  }
  ++vision_writes_;
  if (!masters_ && !signal_frames_) return;
  if (deferred_) {
    pending_.push_back(r.agent);
  } else {
    wake(r.agent);
  }
}

void LaptopLink::wake(int agent) {
  if (signal_frames_) db_->signal_frame(agent);
  if (masters_) masters_->tick(agent);
}

std::size_t LaptopLink::activate() {
  const std::size_t n = pending_.size();
  for (const int agent : pending_) wake(agent);
  pending_.clear();
  return n;
}

void LaptopLink::write_coach(const CoachState& coach) {
  for (CoachItem& c : coach_items_) {
    rtdb::ItemBuffer& b = *c.buffer;
    b.clear();
    const auto set_name = [&](rtdb::Quantity q, const std::string& name, std::size_t index) {
      if (!q) return;
      try {
        b.set(q, name, index);
      } catch (const rtdb::LayoutError& e) {
        if (warned_.insert(name).second) std::fprintf(stderr, "canhil: warning: %s\n", e.what());
      }
    };
    set_name(c.game_state, coach.game_state, 0);
    for (std::size_t k = 0; k < robots_.size() && k < coach.players.size(); ++k) {
      const auto agent = static_cast<std::size_t>(robots_[k]->agent);
      const CoachPlayer& p = coach.players[k];
      b.set(c.running, p.running ? 1.0 : 0.0, agent);
      b.set(c.role_auto, p.role_auto ? 1.0 : 0.0, agent);
      set_name(c.role, p.role, agent);
      set_name(c.attacks, coach.attacks_positive_x ? "positive_x" : "negative_x", agent);
      b.set(c.relocations, static_cast<double>(p.relocations), agent);
    }
    for (const auto& [space, owner] : c.targets) db_->put(space, owner, c.id, b.bytes(), 0);
  }
  ++coach_writes_;
}

void LaptopLink::step(Nanos now, const CoachState& coach) {
  if (now >= next_coach_) {
    if (now > Nanos{0}) write_coach(coach);  // at 0 the constructor just did
    next_coach_ = now + coach_period_;
  }
  if (!replicator_) return;
  if (now >= next_replicate_) {
    replicator_->cycle(now);
    next_replicate_ = now + replicator_->config().period;
  } else {
    replicator_->deliver(now);  // delayed copies due by now
  }
}

void LaptopLink::clear_items(std::size_t robot) {
  const int agent = robots_.at(robot)->agent;
  const rtdb::ItemTable& table = db_->items();
  std::vector<std::byte> zero;
  for (int id = 0; id < table.item_count(); ++id) {
    if (table.kind(agent, id) == rtdb::ItemKind::kNone) continue;
    zero.assign(table.size(id).value_or(0), std::byte{0});
    db_->put(agent, agent, id, zero);
  }
}

void LaptopLink::place(std::size_t robot, const kinematics::Pose& at) {
  Robot& r = *robots_.at(robot);
  if (!r.setpose) {
    const rtdb::ItemLayout& item = rtdb::require(layout_, "CMD_SETPOSE", {"x", "y", "heading", "pending"});
    r.setpose_id = db_->require("CMD_SETPOSE", item.size_bytes(), r.agent);
    r.setpose = std::make_unique<rtdb::ItemBuffer>(item);
  }
  rtdb::ItemBuffer& b = *r.setpose;
  b.set(b.quantity("x"), at.x_m);
  b.set(b.quantity("y"), at.y_m);
  b.set(b.quantity("heading"), at.heading_rad);
  b.set(b.quantity("command"), 0.0);
  b.set(b.quantity("pending"), 1.0);
  db_->put(r.agent, r.agent, r.setpose_id, b.bytes());
}

std::optional<kinematics::Pose> LaptopLink::reported_pose(std::size_t robot) {
  Robot& r = *robots_.at(robot);
  if (!r.pos) return std::nullopt;
  if (!db_->get(r.agent, r.agent, r.pos_id, r.pos->bytes())) return std::nullopt;
  return kinematics::Pose{r.pos->get(r.pos_x), r.pos->get(r.pos_y), r.pos->get(r.pos_heading)};
}

const rtdb::ReplicatorStats* LaptopLink::replicator_stats() const noexcept {
  return replicator_ ? &replicator_->stats() : nullptr;
}

std::string LaptopLink::summary() const {
  std::ostringstream os;
  os << "  RTDB: " << db_->library() << ", layout " << layout_.name() << " (" << layout_.file() << "); "
     << vision_writes_ << " VISION_INFO written, coach written " << coach_writes_ << " times\n";
  if (masters_) {
    os << "  PMan: " << masters_->description() << "\n";
    for (const auto& r : robots_) {
      for (const pman::ProcessCounts& c : masters_->counts(r->agent)) {
        os << "    agent " << r->agent << " " << c.name << ": " << c.activations << " activations, " << c.epilogues
           << " epilogues, " << c.deadline_misses << " deadline misses, " << c.gone
           << " times gone (its process died or left)\n";
      }
    }
  } else {
    os << "  PMan: none (no agent is woken through PMan)\n";
  }
  if (replicator_) {
    const rtdb::ReplicatorStats& s = replicator_->stats();
    os << "  replicator: " << s.cycles << " cycles, " << s.copied << " copies, " << s.lost << " lost\n";
  }
  return os.str();
}

}  // namespace canhil::emulator

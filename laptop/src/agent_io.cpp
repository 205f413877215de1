#include "canhil/laptop/agent_io.hpp"

#include "rtdb_item.hpp"

namespace canhil::laptop {

struct AgentIo::Items {
  Items(rtdb::Database& database, int a) : db(database), agent(a) {}
  rtdb::Database& db;
  int agent;
  Item vision, pos, grabber_info, coach, vel, grabber, kicker;
  int coach_owner = 0;  // the base station's shared copy, else the agent's own
  rtdb::Quantity balls, ball_count, x, y, heading, ball_engaged, game_state;
  rtdb::Quantity vx, vy, va, small, grab, kick, eng_high, eng_low;
  void get(Item& i, int owner) { read_item(db, agent, owner, i); }
  void put(const Item& i) { write_item(db, agent, i); }
};

AgentIo::AgentIo(rtdb::Database& db, const rtdb::Layout& layout, int agent)
    : items_(std::make_unique<Items>(db, agent)) {
  Items& i = *items_;
  i.vision = resolve(db, layout, agent, "VISION_INFO", {"balls", "balls.count"}, true);
  i.balls = i.vision.q("balls");
  i.ball_count = i.vision.q("balls.count");
  i.pos = resolve(db, layout, agent, "CMD_POS", {"x", "y", "heading"}, true);
  i.x = i.pos.q("x");
  i.y = i.pos.q("y");
  i.heading = i.pos.q("heading");
  i.grabber_info = resolve(db, layout, agent, "CMD_GRABBER_INFO", {"ball_engaged"}, true);
  i.ball_engaged = i.grabber_info.q("ball_engaged");
  const rtdb::ItemLayout& coach = rtdb::require(layout, "COACH_INFO", {"game_state"});
  // The base station's copy in this agent's database where the table shares it, else the agent's own.
  const auto coach_id = db.items().id("COACH_INFO");
  i.coach_owner = coach_id && db.items().kind(0, *coach_id) == rtdb::ItemKind::kShared ? 0 : agent;
  i.coach.id = db.require("COACH_INFO", coach.size_bytes(), agent, i.coach_owner);
  i.coach.buf = std::make_unique<rtdb::ItemBuffer>(coach);
  i.game_state = i.coach.q("game_state");
  i.vel = resolve(db, layout, agent, "CMD_VEL", {"vx", "vy", "va"}, true);
  i.vx = i.vel.q("vx");
  i.vy = i.vel.q("vy");
  i.va = i.vel.q("va");
  i.small = i.vel.q("small_adjustment");
  i.grabber = resolve(db, layout, agent, "CMD_GRABBER", {"grabber"}, true);
  i.grab = i.grabber.q("grabber");
  i.kicker = resolve(db, layout, agent, "CMD_KICKER", {"kick"}, true);
  i.kick = i.kicker.q("kick");
  i.eng_high = i.kicker.q("eng_level_high");
  i.eng_low = i.kicker.q("eng_level_low");
}

AgentIo::~AgentIo() = default;

AgentInput AgentIo::read(double dt_s) {
  Items& i = *items_;
  AgentInput in;
  in.dt_s = dt_s;
  i.get(i.vision, i.agent);
  in.ball_seen = i.vision.buf->get(i.ball_count) > 0;
  if (in.ball_seen) {
    const auto b = i.vision.buf->get_point(i.balls, 0);
    in.ball_x_m = b[0];
    in.ball_y_m = b[1];
  }
  i.get(i.pos, i.agent);
  in.x_m = i.pos.buf->get(i.x);
  in.y_m = i.pos.buf->get(i.y);
  in.heading_rad = i.pos.buf->get(i.heading);
  i.get(i.grabber_info, i.agent);
  in.ball_engaged = i.grabber_info.buf->get(i.ball_engaged) != 0;
  // The base station's orders: it plays before any order comes (no state yet) and in "start".
  i.get(i.coach, i.coach_owner);
  const std::string_view state = i.coach.buf->get_enum(i.game_state);
  in.play = i.coach.buf->get(i.game_state) == 0 || state == "start";
  in.their_restart = state.starts_with("their_") && state != "their_goal";  // their_goal: they scored
  return in;
}

void AgentIo::write(const AgentOutput& out) {
  Items& i = *items_;
  rtdb::ItemBuffer& vel = *i.vel.buf;
  vel.set(i.vx, out.vx_mps);
  vel.set(i.vy, out.vy_mps);
  vel.set(i.va, out.va_radps);
  vel.set(i.small, 0.0);
  i.put(i.vel);
  i.grabber.buf->set(i.grab, out.grabber / 100.0);  // the agent's 0..100, the layout's fraction
  i.put(i.grabber);
  if (out.kick != 0) {
    rtdb::ItemBuffer& k = *i.kicker.buf;
    k.set(i.kick, out.kick);
    k.set(i.eng_high, 0.0);
    k.set(i.eng_low, 0.0);
    i.put(i.kicker);
  }
}

}  // namespace canhil::laptop

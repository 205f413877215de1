#include "canhil/frames/messages.hpp"

#include <string>

namespace canhil::frames {
FttInfo read_ftt(const MessageDef& m, const std::string& file) {
  auto fail = [&](const std::string& what) -> DbcError {
    return DbcError(file, m.line, "message " + m.name + " " + what);
  };
  FttInfo info;
  const auto kind = m.attribute_text("FttKind");
  if (!kind) {
    throw fail("has no FttKind attribute; add BA_ \"FttKind\" BO_ " + std::to_string(m.id) +
               " \"sync\"; (or \"async\", \"trigger\")");
  }
  const auto period_ms = m.attribute_int("GenMsgCycleTime").value_or(0);
  const auto gap_ms = m.attribute_int("GenMsgDelayTime").value_or(0);
  if (*kind == "trigger" || *kind == "sync") {
    info.kind = *kind == "trigger" ? FttKind::kTrigger : FttKind::kSync;
    if (period_ms <= 0) {
      throw fail("is " + *kind + " but has no period; set BA_ \"GenMsgCycleTime\" BO_ " + std::to_string(m.id) +
                 " <milliseconds>;");
    }
    info.period = std::chrono::milliseconds(period_ms);
  } else if (*kind == "async") {
    info.kind = FttKind::kAsync;
    if (gap_ms <= 0) {
      throw fail("is async but has no minimum gap; set BA_ \"GenMsgDelayTime\" BO_ " + std::to_string(m.id) +
                 " <milliseconds>;");
    }
    info.min_gap = std::chrono::milliseconds(gap_ms);
  } else {
    throw fail("has FttKind \"" + *kind + "\"; use trigger, sync or async");
  }
  if (info.kind == FttKind::kSync) {
    const auto index = m.attribute_int("FttIndex").value_or(-1);
    if (index < 0 || index > 31) {
      throw fail("is sync but its FttIndex is " + std::to_string(index) +
                 "; give it a bit 0..31 of sync_bitmap with BA_ \"FttIndex\"");
    }
    info.index = static_cast<int>(index);
  }
  return info;
}

MessageSet::MessageSet(Database db) : codec_(std::move(db)) {
  const std::string& file = codec_.database().file;
  int triggers = 0;
  std::array<const MessageDef*, 32> by_index{};
  for (const MessageCodec& mc : codec_.messages()) {
    const FttInfo info = read_ftt(mc.def(), file);
    if (info.kind == FttKind::kTrigger) ++triggers;
    if (info.kind == FttKind::kSync) {
      const MessageDef*& slot = by_index[static_cast<std::size_t>(info.index)];
      if (slot != nullptr) {
        throw DbcError(file, mc.def().line,
                       "message " + mc.def().name + " has FttIndex " + std::to_string(info.index) + " like " +
                           slot->name + "; give each synchronous message its own index");
      }
      slot = &mc.def();
    }
    ftt_.push_back(info);
  }
  if (triggers != 1) {
    throw DbcError(file, 0,
                   "the message set has " + std::to_string(triggers) +
                       " trigger messages (FttKind \"trigger\"); FTT-CAN needs exactly one");
  }
  tm = TypedCodec<Tm>(codec_);
  m1 = TypedCodec<M1>(codec_);
  m3 = {TypedCodec<M3>(codec_, "M3_1"), TypedCodec<M3>(codec_, "M3_2"), TypedCodec<M3>(codec_, "M3_3")};
  m4_1 = TypedCodec<M4_1>(codec_);
  m4_2 = TypedCodec<M4_2>(codec_);
  m5_1 = TypedCodec<M5_1>(codec_);
  m5_2 = TypedCodec<M5_2>(codec_);
  m6_1 = TypedCodec<M6_1>(codec_);
  m6_2 = TypedCodec<M6_2>(codec_);
  m7 = TypedCodec<M7>(codec_);
  m2 = TypedCodec<M2>(codec_);
  m8 = TypedCodec<M8>(codec_);
  m9 = TypedCodec<M9>(codec_);
  m10 = TypedCodec<M10>(codec_);
}

std::shared_ptr<const MessageSet> MessageSet::create(Database db) {
  return std::shared_ptr<const MessageSet>(new MessageSet(std::move(db)));
}

std::shared_ptr<const MessageSet> MessageSet::load(const std::filesystem::path& path) { return create(load_dbc(path)); }

const FttInfo& MessageSet::ftt(const MessageCodec& m) const noexcept {
  const auto i = static_cast<std::size_t>(&m - codec_.messages().data());
  return ftt_[i];
}

const MessageCodec* MessageSet::sync_message(int index) const noexcept {
  for (std::size_t i = 0; i < ftt_.size(); ++i) {
    if (ftt_[i].kind == FttKind::kSync && ftt_[i].index == index) return &codec_.messages()[i];
  }
  return nullptr;
}

}  // namespace canhil::frames

// The control socket: a request in, the reply out, owner-only; a socket left
// by a crashed run is replaced, one in use is not taken over.
// Silent trouble (test::WatchedTest): no step is taken here (the socket's
// requests and replies only); tests/control/commands_test.cpp watches the
// nodes while the same commands run.
#include "canhil/control/unix_server.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "canhil/base/setup_error.hpp"
#include "support/test_paths.hpp"

namespace canhil::control {
namespace {

class UnixServerTest : public ::testing::Test {
 protected:
  UnixServerTest() {
    setenv("RTDB_KEY", std::to_string(0x5E200000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    options_.messages = frames::MessageSet::load(test::shipped_dbc());
    options_.vision_on = false;
    session_ = std::make_unique<emulator::Session>(emulator::plan_run(emulator::Scenario{}, options_));
    commands_ = std::make_unique<Commands>(*session_);
    folder_ = std::filesystem::path(test::build_dir()) / ("control-test-" + std::to_string(getpid()));
    std::filesystem::remove_all(folder_);
  }
  ~UnixServerTest() override { std::filesystem::remove_all(folder_); }
  emulator::SessionOptions options_;
  std::unique_ptr<emulator::Session> session_;
  std::unique_ptr<Commands> commands_;
  std::filesystem::path folder_;
};

TEST_F(UnixServerTest, AnswersARequestAndIsTheOwnersOnly) {
  UnixServer server(folder_ / "control", *commands_);
  const auto reply = nlohmann::json::parse(send_request(server.path(), R"({"command":"snapshot","id":"a"})"));
  EXPECT_EQ(reply["ok"], true);
  EXPECT_EQ(reply["id"], "a");
  EXPECT_EQ(reply["snapshot"]["robots"].size(), 1u);
  struct stat st {};
  ASSERT_EQ(stat(server.path().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  ASSERT_EQ(stat(folder_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  EXPECT_NE(send_request(server.path(), "garbage").find("\"ok\":false"), std::string::npos);
  EXPECT_EQ(server.requests(), 2u);
}

TEST_F(UnixServerTest, ASocketInUseIsNotTakenOverAndAStaleOneIsReplaced) {
  {
    UnixServer first(folder_ / "control", *commands_);
    try {
      UnixServer second(folder_ / "control", *commands_);
      FAIL() << "two runs on one socket";
    } catch (const SetupError& e) {
      EXPECT_NE(std::string(e.what()).find("--control PATH"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(std::filesystem::exists(folder_ / "control")) << "removed when the run ends";
  // A crashed run's socket: a file nobody serves.
  std::filesystem::create_directories(folder_);
  const int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", (folder_ / "control").c_str());
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  close(fd);
  UnixServer replacing(folder_ / "control", *commands_);
  EXPECT_NE(send_request(replacing.path(), R"({"command":"snapshot"})").find("\"ok\":true"), std::string::npos);
}

TEST_F(UnixServerTest, NothingServingIsSaidPlainly) {
  try {
    send_request(folder_ / "nobody", R"({"command":"snapshot"})");
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("is canhil run running"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canhil::control

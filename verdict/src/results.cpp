// Results: as `canhil test` prints them, as a worker sends them back (one
// line of JSON), and many files run in worker processes (verdict.hpp).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/external/match_workers.hpp"
#include "canhil/external/worker.hpp"
#include "canhil/verdict/verdict.hpp"

namespace canhil::verdict {

std::string to_json_line(const FileResult& r) {
  nlohmann::json verdicts = nlohmann::json::array();
  for (const Verdict& v : r.verdicts) {
    verdicts.push_back({{"name", v.name},
                        {"check", v.check},
                        {"line", v.line},
                        {"passed", v.passed},
                        {"measured", v.measured},
                        {"message", v.message}});
  }
  return nlohmann::json{{"file", r.file},          {"name", r.name},           {"error", r.error},
                        {"verdicts", verdicts},    {"virtual_s", r.virtual_s}, {"wall_s", r.wall_s},
                        {"artifacts", r.artifacts}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

FileResult from_json_line(const std::string& line) {
  const nlohmann::json j = nlohmann::json::parse(line);
  FileResult r;
  r.file = j.at("file");
  r.name = j.at("name");
  r.error = j.at("error");
  r.virtual_s = j.at("virtual_s");
  r.wall_s = j.at("wall_s");
  r.artifacts = j.at("artifacts");
  for (const auto& v : j.at("verdicts")) {
    r.verdicts.push_back(
        {v.at("name"), v.at("check"), v.at("line"), v.at("passed"), v.at("measured"), v.at("message")});
  }
  return r;
}

std::string format_result(const FileResult& r) {
  std::ostringstream out;
  char head[256];
  std::snprintf(head, sizeof head, "%s: %s (%.2f s of virtual time in %.2f s)\n", r.file.c_str(),
                r.error.empty() ? (r.passed() ? "passed" : "FAILED") : "ERROR", r.virtual_s, r.wall_s);
  out << head;
  if (!r.error.empty()) out << "  " << r.error << '\n';
  for (const Verdict& v : r.verdicts) {
    out << (v.passed ? "  PASS  " : "  FAIL  ") << v.name << "  (" << v.measured << ")\n";
    if (!v.passed) out << "        " << r.file << ':' << v.line << ": " << v.message << '\n';
  }
  return out.str();
}

bool any_with_processes(const std::vector<std::filesystem::path>& files) {
  for (const auto& f : files) {
    try {
      if (load_test_file(f).external) return true;
    } catch (const SetupError&) {
      // its run says what is wrong with it
    }
  }
  return false;
}

std::vector<FileResult> run_test_files(const std::vector<std::filesystem::path>& files, int jobs,
                                       const TestOptions& options, const std::atomic<bool>& stop,
                                       const std::function<void(const FileResult&)>& each) {
  // Each file's artifacts in a folder of its own: its name; for files of one
  // name, the folders above it too ("processes-score"); a number last where
  // even that is taken (the same file given twice).
  std::vector<TestOptions> each_options(files.size(), options);
  std::set<std::string> taken;
  for (std::size_t k = 0; k < files.size(); ++k) {
    const std::filesystem::path file = files[k].lexically_normal();
    const std::string stem = file.stem().string();
    const auto same = [&](const std::filesystem::path& other) { return other.stem() == file.stem(); };
    std::string name = stem;
    if (std::count_if(files.begin(), files.end(), same) > 1) {
      for (std::filesystem::path up = file.parent_path(); up.has_filename(); up = up.parent_path()) {
        const std::string folder = up.filename().string();
        if (folder == "." || folder == "..") break;
        name = folder + "-" + name;
        if (taken.count(name) == 0) break;
      }
    }
    for (int n = 2; taken.count(name) != 0; ++n) name = stem + "-" + std::to_string(n);
    taken.insert(name);
    each_options[k].artifact_name = name;
  }
  std::vector<FileResult> results;
  const auto done = [&](FileResult r) {
    if (each) each(r);
    results.push_back(std::move(r));
  };
  if (jobs <= 1 || files.size() <= 1) {
    for (const auto& f : files) {
      if (stop) break;
      done(run_test_file(f, each_options[static_cast<std::size_t>(&f - files.data())]));
    }
    return results;
  }
  std::vector<std::uint64_t> indices(files.size());
  for (std::size_t k = 0; k < files.size(); ++k) indices[k] = k;
  external::MatchJobs work;
  work.play = [&](int, std::uint64_t k, const std::function<void(double)>&) {
    return to_json_line(run_test_file(files[k], each_options[k]));
  };
  work.failed = [&](std::uint64_t k, const std::string& why) {
    FileResult r;
    r.file = files[k].string();
    r.name = files[k].stem().string();
    r.error = "its worker process ended: " + why;
    return to_json_line(r);
  };
  work.done = [&](const std::string& line) { done(from_json_line(line)); };
  std::vector<std::string> interfaces;  // every file's robots', on each worker's own bus
  if (options.external || any_with_processes(files)) {
    for (const auto& f : files) {
      try {
        for (const std::string& i : emulator::load_scenario(load_test_file(f).scenario).interfaces) {
          if (std::find(interfaces.begin(), interfaces.end(), i) == interfaces.end()) interfaces.push_back(i);
        }
      } catch (const SetupError&) {
        // its run says what is wrong with it
      }
    }
    external::prepare_external_workers();
    work.enter = [&](int) -> std::shared_ptr<void> { return std::make_shared<external::ExternalWorker>(interfaces); };
    work.play = [&](int, std::uint64_t k, const std::function<void(double)>&) {
      external::ExternalWorker::next_match();  // a fresh IPC namespace: nothing the last file's processes left
      return to_json_line(run_test_file(files[k], each_options[k]));
    };
  }
  external::play_in_workers(indices, jobs, work, stop);
  return results;
}

}  // namespace canhil::verdict

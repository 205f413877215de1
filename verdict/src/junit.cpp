// Test results as JUnit XML (junit.hpp).
#include "canhil/verdict/junit.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "canhil/base/xml_text.hpp"

namespace canhil::verdict {
namespace {

std::string seconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", s);
  return b;
}

// "canhil." and the file's path without .toml, its folders joined by dots
// ("canhil.tests.processes.score"): files of one name in two folders are two
// classes, as a report tool keys its cases on class and name.
std::string classname(const FileResult& r) {
  std::string name;
  std::filesystem::path file = std::filesystem::path(r.file).lexically_normal();
  file.replace_extension();
  for (const auto& part : file) {
    const std::string p = part.string();
    if (p.empty() || p == "/" || p == "." || p == "..") continue;
    name += (name.empty() ? "" : ".") + p;
  }
  return "canhil." + name;
}

}  // namespace

std::string junit_xml(const std::vector<FileResult>& results, const std::string& suite_name) {
  std::size_t tests = 0, failures = 0, errors = 0;
  double time = 0;
  for (const FileResult& r : results) {
    tests += r.error.empty() ? r.verdicts.size() : std::size_t{1};
    failures += r.error.empty() ? r.failures() : std::size_t{0};
    errors += r.error.empty() ? 0U : 1U;
    time += r.wall_s;
  }
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x << "<testsuites name=\"" << xml_escaped(suite_name) << "\" tests=\"" << tests << "\" failures=\"" << failures
    << "\" errors=\"" << errors << "\" time=\"" << seconds(time) << "\">\n";
  for (std::size_t s = 0; s < results.size(); ++s) {
    const FileResult& r = results[s];
    const std::string cls = xml_escaped(classname(r));
    x << "  <testsuite name=\"" << xml_escaped(r.name) << "\" tests=\""
      << (r.error.empty() ? r.verdicts.size() : std::size_t{1}) << "\" failures=\""
      << (r.error.empty() ? r.failures() : std::size_t{0}) << "\" errors=\"" << (r.error.empty() ? 0 : 1)
      << "\" skipped=\"0\" time=\"" << seconds(r.wall_s) << "\" id=\"" << s << "\" package=\"canhil\">\n";
    x << "    <properties>\n      <property name=\"file\" value=\"" << xml_escaped(r.file) << "\"/>\n"
      << "      <property name=\"virtual_s\" value=\"" << seconds(r.virtual_s) << "\"/>\n";
    if (!r.artifacts.empty()) {
      x << "      <property name=\"artifacts\" value=\"" << xml_escaped(r.artifacts) << "\"/>\n";
    }
    x << "    </properties>\n";
    if (!r.error.empty()) {
      x << "    <testcase name=\"" << xml_escaped(r.name) << "\" classname=\"" << cls << "\" time=\""
        << seconds(r.wall_s) << "\">\n      <error type=\"setup\" message=\"" << xml_escaped(r.error) << "\">"
        << xml_escaped(r.error) << "</error>\n    </testcase>\n";
    }
    for (const Verdict& v : r.verdicts) {
      x << "    <testcase name=\"" << xml_escaped(v.name) << "\" classname=\"" << cls << "\" time=\"0\"";
      if (v.passed) {
        x << ">\n      <system-out>" << xml_escaped(v.measured) << "</system-out>\n    </testcase>\n";
        continue;
      }
      x << ">\n      <failure type=\"" << xml_escaped(v.check) << "\" message=\"" << xml_escaped(v.message) << "\">"
        << xml_escaped(r.file + ":" + std::to_string(v.line) + ": " + v.message + "\nmeasured: " + v.measured)
        << "</failure>\n    </testcase>\n";
    }
    x << "  </testsuite>\n";
  }
  x << "</testsuites>\n";
  return x.str();
}

}  // namespace canhil::verdict

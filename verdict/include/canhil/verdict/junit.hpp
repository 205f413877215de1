// canhil/verdict/junit.hpp — test results as JUnit XML, the report GitHub
// Actions, GitLab CI and Jenkins read: one <testsuite> per test file, one
// <testcase> per expectation, a failing one with its <failure> (the message
// and what was measured), a file that could not run with one <error>. It
// follows Jenkins' JUnit schema (junit-4.xsd, which the tests check it
// against with xmllint).
#pragma once

#include <string>
#include <vector>

#include "canhil/verdict/verdict.hpp"

namespace canhil::verdict {

/// The report of `results`, `suite_name` naming the whole (<testsuites
/// name>); every text in it base/xml_text.hpp's xml_escaped.
std::string junit_xml(const std::vector<FileResult>& results, const std::string& suite_name = "canhil test");

}  // namespace canhil::verdict

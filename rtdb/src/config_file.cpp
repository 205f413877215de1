#include "canhil/rtdb/config_file.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace canhil::rtdb {
namespace {

struct Token {
  std::string text;
  int line;
};

// Words (identifiers and header paths), and the punctuation = , ; { }.
std::vector<Token> tokenize(const std::string& text, const std::string& file) {
  std::vector<Token> out;
  int line = 1;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c)) != 0) {
      ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (c == '=' || c == ',' || c == ';' || c == '{' || c == '}') {
      out.push_back({std::string(1, c), line});
      ++i;
    } else if (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '/' || c == '-') {
      std::size_t j = i;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) != 0 || text[j] == '_' ||
                                 text[j] == '.' || text[j] == '/' || text[j] == '-')) {
        ++j;
      }
      out.push_back({text.substr(i, j - i), line});
      i = j;
    } else {
      throw RtdbConfigError(file, line, std::string("unexpected character '") + c + "'");
    }
  }
  return out;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || (std::isalpha(static_cast<unsigned char>(s[0])) == 0 && s[0] != '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; });
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, std::string file) : t_(std::move(tokens)), file_(std::move(file)) {}

  RtdbConfig parse() {
    RtdbConfig c;
    c.file = file_;
    std::vector<std::pair<std::string, std::vector<std::string>>> assignments;
    std::vector<int> assignment_lines;
    bool have_agents = false;
    while (pos_ < t_.size()) {
      const Token kw = next("a section (AGENTS, ITEM, SCHEMA or ASSIGNMENT)");
      if (kw.text == "AGENTS") {
        if (have_agents) fail(kw.line, "AGENTS is given twice; list every agent once");
        have_agents = true;
        expect("=");
        c.agents = list("an agent name");
        accept(";");
        std::set<std::string> seen;
        for (const auto& a : c.agents) {
          if (!seen.insert(a).second) fail(kw.line, "agent " + a + " is listed twice");
        }
      } else if (kw.text == "ITEM") {
        ItemDecl item;
        item.line = kw.line;
        item.name = identifier("the item name");
        expect("{");
        while (!accept("}")) {
          const Token key = next("datatype, headerfile or period");
          expect("=");
          const Token value = next("a value for " + key.text);
          accept(";");
          if (key.text == "datatype") {
            if (!is_identifier(value.text)) fail(value.line, "datatype \"" + value.text + "\" is not a C type name");
            item.datatype = value.text;
          } else if (key.text == "headerfile") {
            item.headerfile = value.text;
          } else if (key.text == "period") {
            try {
              item.period = std::stoi(value.text);
            } catch (const std::exception&) {
              item.period = 0;
            }
            if (item.period < 1) fail(value.line, "period of " + item.name + " must be a whole number, 1 or more");
          } else {
            fail(key.line, "unknown item field \"" + key.text + "\"; use datatype, headerfile or period");
          }
        }
        if (item.datatype.empty()) fail(item.line, "item " + item.name + " has no datatype; add `datatype = TYPE;`");
        if (item.headerfile.empty()) item.headerfile = item.datatype + ".h";
        for (const auto& other : c.items) {
          if (other.name == item.name) fail(item.line, "item " + item.name + " is declared twice");
        }
        c.items.push_back(item);
      } else if (kw.text == "SCHEMA") {
        SchemaDecl s;
        s.line = kw.line;
        s.name = identifier("the schema name");
        expect("{");
        while (!accept("}")) {
          const Token key = next("shared or local");
          expect("=");
          auto names = list("an item name");
          accept(";");
          if (key.text == "shared") {
            s.shared.insert(s.shared.end(), names.begin(), names.end());
          } else if (key.text == "local") {
            s.local.insert(s.local.end(), names.begin(), names.end());
          } else {
            fail(key.line, "unknown schema field \"" + key.text + "\"; use shared or local");
          }
        }
        for (const auto& other : c.schemas) {
          if (other.name == s.name) fail(s.line, "schema " + s.name + " is declared twice");
        }
        c.schemas.push_back(s);
      } else if (kw.text == "ASSIGNMENT") {
        expect("{");
        std::string schema;
        std::vector<std::string> agents;
        while (!accept("}")) {
          const Token key = next("schema or agents");
          expect("=");
          if (key.text == "schema") {
            schema = identifier("the schema name");
          } else if (key.text == "agents") {
            agents = list("an agent name");
          } else {
            fail(key.line, "unknown assignment field \"" + key.text + "\"; use schema or agents");
          }
          accept(";");
        }
        if (schema.empty()) fail(kw.line, "ASSIGNMENT has no schema; add `schema = NAME;`");
        assignments.emplace_back(schema, agents);
        assignment_lines.push_back(kw.line);
      } else {
        fail(kw.line, "unknown section \"" + kw.text + "\"; sections are AGENTS, ITEM, SCHEMA and ASSIGNMENT");
      }
    }
    if (!have_agents || c.agents.empty()) fail(1, "no AGENTS list; start with `AGENTS = NAME, ...;`");
    // Schemas name declared items, each once.
    for (const auto& s : c.schemas) {
      std::set<std::string> seen;
      for (const auto* list : {&s.shared, &s.local}) {
        for (const auto& name : *list) {
          if (std::none_of(c.items.begin(), c.items.end(), [&](const ItemDecl& i) { return i.name == name; })) {
            fail(s.line, "schema " + s.name + " names item " + name + ", which no ITEM declares");
          }
          if (!seen.insert(name).second) fail(s.line, "schema " + s.name + " lists item " + name + " twice");
        }
      }
    }
    c.agent_schema.assign(c.agents.size(), -1);
    for (std::size_t k = 0; k < assignments.size(); ++k) {
      const std::string& schema = assignments[k].first;
      const std::vector<std::string>& agents = assignments[k].second;
      const auto s =
          std::find_if(c.schemas.begin(), c.schemas.end(), [&](const SchemaDecl& d) { return d.name == schema; });
      if (s == c.schemas.end())
        fail(assignment_lines[k], "ASSIGNMENT names schema " + schema + ", which is not declared");
      for (const auto& a : agents) {
        const auto at = std::find(c.agents.begin(), c.agents.end(), a);
        if (at == c.agents.end())
          fail(assignment_lines[k], "ASSIGNMENT names agent " + a + ", which AGENTS does not list");
        int& slot = c.agent_schema[static_cast<std::size_t>(at - c.agents.begin())];
        if (slot >= 0) fail(assignment_lines[k], "agent " + a + " is assigned two schemas; give it one");
        slot = static_cast<int>(s - c.schemas.begin());
      }
    }
    for (std::size_t a = 0; a < c.agents.size(); ++a) {
      if (c.agent_schema[a] < 0) fail(1, "agent " + c.agents[a] + " has no ASSIGNMENT; assign it a schema");
    }
    c.membership.assign(c.agents.size(), std::vector<int>(c.items.size(), -1));
    for (std::size_t a = 0; a < c.agents.size(); ++a) {
      const SchemaDecl& s = c.schemas[static_cast<std::size_t>(c.agent_schema[a])];
      for (std::size_t i = 0; i < c.items.size(); ++i) {
        const std::string& n = c.items[i].name;
        if (std::find(s.shared.begin(), s.shared.end(), n) != s.shared.end()) c.membership[a][i] = 1;
        if (std::find(s.local.begin(), s.local.end(), n) != s.local.end()) c.membership[a][i] = 0;
      }
    }
    return c;
  }

 private:
  [[noreturn]] void fail(int line, const std::string& m) const { throw RtdbConfigError(file_, line, m); }
  Token next(const std::string& what) {
    if (pos_ >= t_.size()) fail(t_.empty() ? 1 : t_.back().line, "the file ends where " + what + " was expected");
    return t_[pos_++];
  }
  void expect(const std::string& s) {
    const Token t = next("'" + s + "'");
    if (t.text != s) fail(t.line, "expected '" + s + "', found \"" + t.text + "\"");
  }
  bool accept(const std::string& s) {
    if (pos_ < t_.size() && t_[pos_].text == s) {
      ++pos_;
      return true;
    }
    return false;
  }
  std::string identifier(const std::string& what) {
    const Token t = next(what);
    if (!is_identifier(t.text)) fail(t.line, "expected " + what + ", found \"" + t.text + "\"");
    return t.text;
  }
  std::vector<std::string> list(const std::string& what) {
    std::vector<std::string> out{identifier(what)};
    while (accept(",")) out.push_back(identifier(what));
    return out;
  }

  std::vector<Token> t_;
  std::string file_;
  std::size_t pos_ = 0;
};

}  // namespace

RtdbConfig parse_rtdb_config(const std::string& text, const std::string& file) {
  return Parser(tokenize(text, file), file).parse();
}

RtdbConfig load_rtdb_config(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw RtdbConfigError(path.string(), 0, "cannot read the RTDB configuration (does it exist?)");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_rtdb_config(s.str(), path.string());
}

std::string generate_user_header(const RtdbConfig& c) {
  std::ostringstream os;
  os << "/* Generated from " << c.file << " by canhil-rtdb-gen. Do not edit: edit the configuration. */\n"
     << "#ifndef RTDB_USER_H\n#define RTDB_USER_H\n\n/* Agents (the AGENT environment variable takes these numbers). "
        "*/\n";
  for (std::size_t a = 0; a < c.agents.size(); ++a) os << "#define " << c.agents[a] << " " << a << "\n";
  os << "#define N_AGENTS " << c.agents.size() << "\n\n/* Items. */\n";
  for (std::size_t i = 0; i < c.items.size(); ++i) os << "#define " << c.items[i].name << " " << i << "\n";
  os << "#define N_ITEMS " << c.items.size() << "\n\n#endif\n";
  return os.str();
}

std::string generate_config_source(const RtdbConfig& c) {
  std::ostringstream os;
  os << "/* Generated from " << c.file << " by canhil-rtdb-gen. Do not edit: edit the configuration. */\n"
     << "#include <stdint.h>\n\n#include \"canhil/rtdb/rtdb_table.h\"\n";
  std::set<std::string> headers;
  for (const auto& i : c.items) {
    if (headers.insert(i.headerfile).second) os << "#include \"" << i.headerfile << "\"\n";
  }
  os << "\nstatic const canhil_rtdb_item items[] = {\n";
  for (const auto& i : c.items) {
    os << "    {\"" << i.name << "\", (uint32_t)sizeof(" << i.datatype << "), " << i.period << "},\n";
  }
  os << "};\n\n";
  for (std::size_t a = 0; a < c.agents.size(); ++a) {
    os << "static const int8_t membership_" << a << "[] = {";
    for (std::size_t i = 0; i < c.items.size(); ++i) os << (i ? ", " : "") << c.membership[a][i];
    os << "};\n";
  }
  os << "\nstatic const canhil_rtdb_agent agents[] = {\n";
  for (std::size_t a = 0; a < c.agents.size(); ++a) os << "    {\"" << c.agents[a] << "\", membership_" << a << "},\n";
  os << "};\n\nconst canhil_rtdb_table canhil_rtdb_config = {" << c.agents.size() << ", " << c.items.size()
     << ", agents, items, \"" << c.file << "\"};\n";
  return os.str();
}

}  // namespace canhil::rtdb

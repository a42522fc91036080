#include "applications/framework/scene.h"

#include "applications/framework/scenario.h"
#include "base/exceptions.h"

#include <deal.II/base/exceptions.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

namespace spinesim::framework {

namespace {

std::string collapse_whitespace(const std::string& in) {
  std::string out;
  bool space = false;
  for (const char c : in) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      space = !out.empty();
    } else {
      if (space)
        out += ' ';
      out += c;
      space = false;
    }
  }
  return out;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string join(const std::vector<std::string>& parts, const std::string& sep) {
  std::string out;
  for (const auto& p : parts)
    out += (out.empty() ? "" : sep) + p;
  return out;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Byte offset of the first byte in `s` that does not belong to well-formed UTF-8 (RFC 3629:
// no overlong forms, no surrogates, nothing above U+10FFFF), or npos. deal.II keeps a value's
// bytes as they are, and the JSON the scene's parameters are walked through must be UTF-8.
std::size_t first_invalid_utf8(const std::string& s) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(s[i]); };
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = byte(i);
    std::size_t n;
    unsigned char lo = 0x80, hi = 0xBF; // the allowed range of the second byte
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      n = 1;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 2;
      lo = c == 0xE0 ? 0xA0 : 0x80;
      hi = c == 0xED ? 0x9F : 0xBF;
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 3;
      lo = c == 0xF0 ? 0x90 : 0x80;
      hi = c == 0xF4 ? 0x8F : 0xBF;
    } else {
      return i;
    }
    if (i + n >= s.size()) // the sequence runs past the end
      return i;
    for (std::size_t k = 1; k <= n; ++k) {
      const unsigned char b = byte(i + k);
      if (k == 1 ? (b < lo || b > hi) : (b < 0x80 || b > 0xBF))
        return i;
    }
    i += n + 1;
  }
  return std::string::npos;
}

// Bad input naming the byte at offset `bad` of `text` (from first_invalid_utf8).
[[noreturn]] void throw_not_utf8(const std::string& text, std::size_t bad,
                                 const std::string& where) {
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned char>(text[bad]));
  throw InvalidInput(where,
                     "byte " + std::string(hex) + " at column " + std::to_string(bad + 1) +
                         " is not UTF-8 text",
                     "UTF-8 text (plain ASCII suffices for every parameter)");
}

void require_utf8(const std::string& text, const std::string& where) {
  const std::size_t bad = first_invalid_utf8(text);
  if (bad != std::string::npos)
    throw_not_utf8(text, bad, where);
}

// Subsection path in effect at 1-based `line` of a .prm text (before that line's own words).
std::vector<std::string> subsection_path_at(const std::string& text, unsigned int line) {
  std::vector<std::string> path;
  std::istringstream in(text);
  std::string raw;
  for (unsigned int n = 1; n < line && std::getline(in, raw); ++n) {
    std::string l = trim(raw.substr(0, raw.find('#')));
    if (l.rfind("subsection ", 0) == 0)
      path.push_back(collapse_whitespace(l.substr(11)));
    else if (l == "end" && !path.empty())
      path.pop_back();
  }
  return path;
}

// `include FILE` lines of a .prm text, expanded in place. `origins` receives "file:line" for
// every line of the result, so parse errors name the file a line came from.
constexpr unsigned int max_include_depth = 16;
// A scene is a page of text; anything larger (or a device such as /dev/zero) is not one.
constexpr std::uintmax_t max_scene_bytes = 16u << 20;

void expand_includes(const std::string& text, const std::filesystem::path& file,
                     std::vector<std::filesystem::path>& stack, std::string& out,
                     std::vector<std::string>& origins) {
  namespace fs = std::filesystem;
  std::istringstream in(text);
  std::string raw;
  for (unsigned int n = 1; std::getline(in, raw); ++n) {
    const std::string where = file.string() + ":" + std::to_string(n);
    require_utf8(raw, where);
    const std::string l = trim(raw.substr(0, raw.find('#')));
    if (l.rfind("include", 0) != 0 ||
        (l.size() > 7 && !std::isspace(static_cast<unsigned char>(l[7])))) {
      out += raw + "\n";
      origins.push_back(where);
      continue;
    }
    fs::path target = trim(l.substr(7));
    if (target.empty())
      throw InvalidInput(where, "include without a file name", "include FILE (a .prm file)");
    if (target.is_relative())
      target = file.parent_path() / target;
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(target, ec);
    for (const auto& open : stack)
      if (open == canonical)
        throw InvalidInput(where, "includes " + target.string() + ", which includes it again",
                           "includes without cycles");
    if (stack.size() >= max_include_depth)
      throw InvalidInput(where, "includes nested deeper than " + std::to_string(max_include_depth),
                         "at most " + std::to_string(max_include_depth) + " levels");
    if (!fs::is_regular_file(target, ec) || fs::file_size(target, ec) > max_scene_bytes)
      throw InvalidInput(where, "cannot include " + target.string(),
                         "an existing .prm file of at most 16 MiB, relative to the including file");
    std::ifstream included(target);
    if (!included)
      throw InvalidInput(where, "cannot open included file " + target.string(),
                         "an existing .prm file, relative to the including file");
    std::stringstream buffer;
    buffer << included.rdbuf();
    stack.push_back(canonical);
    expand_includes(buffer.str(), target, stack, out, origins);
    stack.pop_back();
  }
}

} // namespace

Scene::Scene() {
  prm_.declare_entry("Dimension", "2", dealii::Patterns::Integer(2, 3),
                     "Spatial dimension of the run: 2 (plane strain/stress) or 3 [-].");
  prm_.declare_entry("Scenario", "simulation",
                     dealii::Patterns::Selection(Scenarios::instance().names("|")),
                     "What the run does. " + Scenarios::instance().documentation());
  prm_.declare_entry("Description", "", dealii::Patterns::Anything(),
                     "One line saying what the run is for; copied into summary.json [-].");
  prm_.enter_subsection("Effects");
  Effects::declare(prm_);
  prm_.leave_subsection();
  SectionDeclarer sections(prm_);
  for (const auto& [name, entry] : Scenarios::instance().entries())
    for (const auto& section : entry.sections)
      sections.declare(section.name, section.declare);
}

void Scene::load_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && (!std::filesystem::is_regular_file(path, ec) ||
                                            std::filesystem::file_size(path, ec) > max_scene_bytes))
    throw InvalidInput(path, "not a scene file (not a regular file, or over 16 MiB)",
                       "a .prm or .json file");
  std::ifstream in(path);
  if (!in)
    throw InvalidInput(path, "cannot open the scene file",
                       "an existing, readable .prm or .json file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  source_name_ = path;
  if (ends_with(path, ".json")) {
    // deal.II's JSON reader (Boost property_tree) lets overlong forms and surrogates through,
    // which the parameter walks (nlohmann) refuse later: checked here, line by line.
    {
      std::istringstream lines(buffer.str());
      std::string line;
      for (unsigned int n = 1; std::getline(lines, line); ++n)
        require_utf8(line, path + ":" + std::to_string(n));
    }
    try {
      std::istringstream json(buffer.str());
      prm_.parse_input_from_json(json, /*skip_undefined=*/false);
    } catch (const dealii::ExceptionBase& e) {
      std::ostringstream msg;
      e.print_info(msg);
      throw InvalidInput(path, collapse_whitespace(msg.str()),
                         "the sections and entries listed by `spinesim params --format json`");
    } catch (const std::exception& e) {
      throw InvalidInput(path, collapse_whitespace(e.what()),
                         "valid JSON with the structure of `spinesim params --format json`");
    }
    return;
  }
  if (!ends_with(path, ".prm"))
    throw InvalidInput(path, "unknown scene file type", ".prm or .json");
  std::vector<std::filesystem::path> stack{std::filesystem::weakly_canonical(path)};
  std::string expanded;
  std::vector<std::string> origins;
  expand_includes(buffer.str(), path, stack, expanded, origins);
  line_origins_ = std::move(origins);
  load_text(expanded, path);
  line_origins_.clear();
  resolve_file_parameters(std::filesystem::path(path).parent_path().string());
}

void Scene::resolve_file_parameters(const std::string& directory) {
  namespace fs = std::filesystem;
  if (directory.empty())
    return; // the scene is in the working directory: nothing to resolve
  std::ostringstream out;
  prm_.print_parameters(out, dealii::ParameterHandler::JSON);
  std::vector<std::string> path;
  std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& node) {
    for (const auto& [key, value] : node.items()) {
      if (!value.contains("value")) {
        path.push_back(key);
        walk(value);
        path.pop_back();
        continue;
      }
      const std::string v = value["value"].get<std::string>();
      if (value["pattern_description"].get<std::string>().find("FileName") == std::string::npos ||
          v.empty() || fs::path(v).is_absolute() || !fs::exists(fs::path(directory) / v))
        continue;
      for (const auto& p : path)
        prm_.enter_subsection(p);
      prm_.set(key, (fs::path(directory) / v).lexically_normal().string());
      for (std::size_t i = 0; i < path.size(); ++i)
        prm_.leave_subsection();
    }
  };
  walk(nlohmann::json::parse(out.str()));
}

std::vector<std::string> Scene::input_files() const {
  namespace fs = std::filesystem;
  std::ostringstream out;
  prm_.print_parameters(out, dealii::ParameterHandler::JSON);
  std::vector<std::string> files;
  std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& node) {
    for (const auto& [key, value] : node.items()) {
      if (!value.contains("value")) {
        walk(value);
        continue;
      }
      const std::string v = value["value"].get<std::string>();
      std::error_code ec;
      const std::string pattern = value["pattern_description"].get<std::string>();
      if (pattern.find("FileName") != std::string::npos &&
          pattern.find("input") != std::string::npos && !v.empty() && fs::is_regular_file(v, ec))
        files.push_back(v);
    }
  };
  walk(nlohmann::json::parse(out.str()));
  return files;
}

void Scene::load_text(const std::string& text, const std::string& name) {
  source_name_ = name;
  std::istringstream in(text);
  try {
    prm_.parse_input(in, name);
  } catch (const dealii::ExceptionBase& e) {
    std::ostringstream msg;
    e.print_info(msg);
    rethrow_parse_error(msg.str(), text);
  }
}

void Scene::rethrow_parse_error(const std::string& deal_message, const std::string& text) const {
  const std::string message = collapse_whitespace(deal_message);
  std::smatch m;
  const std::regex line_re(R"(Line <(\d+)> of file <(.*?)>?:\s*(.*))");
  if (!std::regex_search(message, m, line_re))
    throw InvalidInput(source_name_, message, "");
  const unsigned int line = std::stoul(m[1]);
  const std::string detail = m[3];
  const std::vector<std::string> path = subsection_path_at(text, line);
  const std::string origin = line >= 1 && line <= line_origins_.size()
                                 ? line_origins_[line - 1]
                                 : std::string(m[2]) + ":" + std::to_string(line);
  const std::string where =
      origin + (path.empty() ? "" : " (in subsection " + join(path, "/") + ")");
  // An unknown name: list what this subsection has. A bad value: deal.II already names the
  // pattern, which is what is allowed.
  if (detail.find("No entry with name") != std::string::npos ||
      detail.find("There is no subsection") != std::string::npos ||
      detail.find("no such subsection") != std::string::npos)
    throw InvalidInput(where, detail, allowed_names(path));
  throw InvalidInput(where, detail, "");
}

std::string Scene::allowed_names(const std::vector<std::string>& path) const {
  std::ostringstream out;
  prm_.print_parameters(out, dealii::ParameterHandler::JSON);
  nlohmann::json node = nlohmann::json::parse(out.str());
  for (const auto& p : path) {
    if (!node.contains(p))
      return "";
    node = node[p];
  }
  std::vector<std::string> entries, sections;
  for (const auto& [key, value] : node.items())
    (value.contains("value") ? entries : sections).push_back(key);
  std::string allowed;
  if (!entries.empty())
    allowed += "entries: " + join(entries, ", ");
  if (!sections.empty())
    allowed += std::string(allowed.empty() ? "" : "; ") + "subsections: " + join(sections, ", ");
  return allowed;
}

void Scene::apply_override(const std::string& assignment) {
  const std::string where = "--set \"" + assignment + "\"";
  const auto eq = assignment.find('=');
  // Named by its parameter when the bad byte is in the value (the name is then plain text).
  const std::size_t bad = first_invalid_utf8(assignment);
  if (bad != std::string::npos)
    throw_not_utf8(assignment, bad,
                   eq != std::string::npos && bad > eq ? "--set " + assignment.substr(0, eq)
                                                       : std::string("--set"));
  if (eq == std::string::npos)
    throw InvalidInput(where, "no '=' in the override", "\"Section/Sub/Parameter=value\"");
  std::vector<std::string> path;
  std::stringstream ss(assignment.substr(0, eq));
  std::string part;
  while (std::getline(ss, part, '/'))
    path.push_back(collapse_whitespace(part));
  const std::string value = trim(assignment.substr(eq + 1));
  const std::string entry = path.back();
  path.pop_back();

  std::ostringstream out;
  prm_.print_parameters(out, dealii::ParameterHandler::JSON);
  nlohmann::json node = nlohmann::json::parse(out.str());
  std::vector<std::string> walked;
  for (const auto& p : path) {
    if (!node.contains(p) || node[p].contains("value"))
      throw InvalidInput(
          where, "no subsection '" + p + "'" + (walked.empty() ? "" : " in " + join(walked, "/")),
          allowed_names(walked));
    node = node[p];
    walked.push_back(p);
  }
  if (!node.contains(entry) || !node[entry].contains("value"))
    throw InvalidInput(
        where, "no parameter '" + entry + "'" + (walked.empty() ? "" : " in " + join(walked, "/")),
        allowed_names(walked));
  for (const auto& p : path)
    prm_.enter_subsection(p);
  try {
    prm_.set(entry, value);
  } catch (const dealii::ExceptionBase&) {
    for (std::size_t i = 0; i < path.size(); ++i)
      prm_.leave_subsection();
    throw InvalidInput(where, "value '" + value + "' does not fit",
                       node[entry]["pattern_description"].get<std::string>());
  }
  for (std::size_t i = 0; i < path.size(); ++i)
    prm_.leave_subsection();
}

int Scene::dimension() const {
  return prm_.get_integer("Dimension");
}
std::string Scene::scenario() const {
  return prm_.get("Scenario");
}
std::string Scene::description() const {
  return prm_.get("Description");
}

Effects Scene::effects() const {
  Effects effects;
  effects.parse(prm_);
  effects.check_consistency();
  return effects;
}

std::string Scene::resolved_prm() const {
  std::ostringstream out;
  out << "# Resolved parameters of scene " << source_name_ << "\n";
  prm_.print_parameters(out, dealii::ParameterHandler::PRM |
                                 dealii::ParameterHandler::KeepDeclarationOrder);
  return out.str();
}

namespace {
// Unit from a help text's trailing "[unit]".
std::string unit_of(const std::string& doc) {
  const auto close = doc.rfind(']');
  const auto open = doc.rfind('[', close);
  if (close == std::string::npos || open == std::string::npos)
    return "";
  return doc.substr(open + 1, close - open - 1);
}

void markdown(const nlohmann::json& node, const std::string& path, std::ostream& out) {
  bool header = false;
  for (const auto& [key, value] : node.items()) {
    if (!value.contains("value"))
      continue;
    if (!header) {
      out << "\n## " << (path.empty() ? "(top level)" : path) << "\n\n"
          << "| parameter | default | allowed | unit | meaning |\n|---|---|---|---|---|\n";
      header = true;
    }
    std::string doc = value["documentation"].get<std::string>();
    std::string pattern = value["pattern_description"].get<std::string>();
    for (auto* s : {&doc, &pattern})
      for (auto& c : *s)
        if (c == '|' || c == '\n')
          c = c == '|' ? '/' : ' ';
    out << "| " << key << " | `" << value["default_value"].get<std::string>() << "` | " << pattern
        << " | " << unit_of(doc) << " | " << doc << " |\n";
  }
  for (const auto& [key, value] : node.items())
    if (!value.contains("value"))
      markdown(value, path.empty() ? key : path + "/" + key, out);
}
} // namespace

std::string Scene::listing(const std::string& format) const {
  std::ostringstream out;
  if (format == "prm") {
    prm_.print_parameters(out, dealii::ParameterHandler::PRM |
                                   dealii::ParameterHandler::KeepDeclarationOrder);
  } else if (format == "json") {
    prm_.print_parameters(out, dealii::ParameterHandler::JSON);
  } else if (format == "md") {
    std::ostringstream json;
    prm_.print_parameters(json, dealii::ParameterHandler::JSON);
    out << "# spinesim parameter reference\n\nGenerated by `spinesim params --format md` from the "
           "declarations in the code. Units are in brackets at the end of each help text.\n";
    markdown(nlohmann::json::parse(json.str()), "", out);
  } else {
    throw InvalidInput("--format", "unknown format '" + format + "'", "prm|json|md");
  }
  return out.str();
}

} // namespace spinesim::framework

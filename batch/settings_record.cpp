#include "batch/settings_record.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace kanesim::batch {
namespace {

bool Informational(const std::string& key) {
  for (const char* k : kInformationalKeys)
    if (key == k) return true;
  return false;
}

std::string TrimSpaces(const std::string& s) {
  const size_t b = s.find_first_not_of(' '), e = s.find_last_not_of(' ');
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

}  // namespace

void SettingsRecord::Set(const std::string& key, const std::string& value) {
  for (auto& [k, v] : entries)
    if (k == key) {
      v = value;
      return;
    }
  entries.emplace_back(key, value);
}

const std::string* SettingsRecord::Find(const std::string& key) const {
  for (const auto& [k, v] : entries)
    if (k == key) return &v;
  return nullptr;
}

std::string SettingsPathFor(const std::string& summary_path) {
  return std::filesystem::path(summary_path).replace_extension(".settings").string();
}

std::string ScenariosPathFor(const std::string& summary_path) {
  return std::filesystem::path(summary_path).replace_extension(".scenarios").string();
}

std::string FormatSettings(const SettingsRecord& record) {
  std::string s =
      "# kanesim sweep settings: what the summary beside this file was made with.\n"
      "# sweep --resume and sweep merge refuse to mix summaries whose settings differ.\n";
  for (const auto& [k, v] : record.entries) s.append(k).append(" = ").append(v).append("\n");
  return s;
}

bool ReadSettings(const std::string& path, SettingsRecord* out, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot read '" + path + "'";
    return false;
  }
  *out = SettingsRecord{};
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const size_t eq = line.find(" = ");
    if (eq == std::string::npos) {
      *error = path + ":" + std::to_string(n) + ": expected 'key = value'";
      return false;
    }
    out->Set(TrimSpaces(line.substr(0, eq)), TrimSpaces(line.substr(eq + 3)));
  }
  return true;
}

std::vector<std::string> SettingsDifferences(const SettingsRecord& recorded, const SettingsRecord& now,
                                             const std::string& recorded_name, const std::string& now_name) {
  std::vector<std::string> out;
  auto shown = [](const std::string* v) { return v ? (v->empty() ? std::string("(empty)") : *v) : "(not recorded)"; };
  std::vector<std::string> keys;
  for (const auto& [k, v] : now.entries) keys.push_back(k);
  for (const auto& [k, v] : recorded.entries)
    if (!now.Find(k)) keys.push_back(k);
  for (const std::string& k : keys) {
    if (Informational(k)) continue;
    const std::string* a = recorded.Find(k);
    const std::string* b = now.Find(k);
    if (a && b && *a == *b) continue;
    out.push_back(k + ": " + shown(a) + " (" + recorded_name + "), " + shown(b) + " (" + now_name + ")");
  }
  return out;
}

}  // namespace kanesim::batch

#include "primlabel/service/model_registry.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <optional>
#include <sstream>

#include "primlabel/ops/logging.hpp"
#include "primlabel/service/repository_path.hpp"
#include "primlabel/service/user_text.hpp"
#include "primlabel/v1/model.pb.h"

namespace primlabel::service {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMagicBytes = 16;  // "PRIMLABEL-MODEL\n", checked by parse_model

std::int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Model and version names become directory names: no separators, no "." or "..".
void check_name(const std::string& what, const std::string& name) {
  if (name.empty() || name == "." || name == ".." || name.size() > 200 ||
      name.find_first_of("/\\") != std::string::npos || name.find('\0') != std::string::npos)
    throw RegistryError(RegistryError::Kind::kInvalidArgument,
                        "invalid " + what + " name '" + user_text(name) + "'");
}

// " version 'v'" when a version is named.
std::string version_part(const std::string& version) {
  return version.empty() ? "" : " version '" + user_text(version) + "'";
}

// The entries of a directory; an unreadable one has none (it counts as missing).
std::vector<fs::directory_entry> entries_of(const fs::path& dir) {
  std::vector<fs::directory_entry> entries;
  std::error_code error;
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error))
    entries.push_back(*it);
  return entries;
}

bool hidden(const fs::path& path) {
  const std::string name = path.filename().string();
  return name.empty() || name[0] == '.';
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError(path.string() + ": cannot open");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// The file's own description of the model (everything but the weights).
v1::ModelMetadata metadata_of(const std::string& bytes, const std::string& name,
                              const std::string& version, const std::string& relative_path) {
  v1::ModelEnvelope envelope;
  v1::Model model;
  if (bytes.size() < kMagicBytes ||
      !envelope.ParseFromArray(bytes.data() + kMagicBytes, int(bytes.size() - kMagicBytes)) ||
      !model.ParseFromString(envelope.model()))
    throw ModelError(relative_path + ": cannot read the model description");
  v1::ModelMetadata metadata;
  metadata.set_name(name);
  metadata.set_version(version);
  metadata.set_kind(model.kind());
  *metadata.mutable_classes() = model.classes();
  *metadata.mutable_features() = model.features();
  *metadata.mutable_graph() = model.graph();
  *metadata.mutable_inference() = model.inference();
  *metadata.mutable_training() = model.training();
  *metadata.mutable_validation() = model.validation();
  metadata.set_created_unix_ms(model.created_unix_ms());
  metadata.set_created_by(model.created_by());
  metadata.set_path(relative_path);
  metadata.set_model_crc32(envelope.model_crc32());
  return metadata;
}

}  // namespace

bool version_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i]));
    const bool db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      std::size_t ei = i, ej = j;
      while (ei < a.size() && std::isdigit(static_cast<unsigned char>(a[ei]))) ++ei;
      while (ej < b.size() && std::isdigit(static_cast<unsigned char>(b[ej]))) ++ej;
      // Compare by value: strip leading zeros, then the longer run is larger.
      std::size_t zi = i, zj = j;
      while (zi + 1 < ei && a[zi] == '0') ++zi;
      while (zj + 1 < ej && b[zj] == '0') ++zj;
      if (ei - zi != ej - zj) return ei - zi < ej - zj;
      const int order = a.compare(zi, ei - zi, b, zj, ej - zj);
      if (order != 0) return order < 0;
      if (ei - i != ej - j) return ei - i < ej - j;  // "01" after "1": deterministic
      i = ei, j = ej;
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
    ++i, ++j;
  }
  return a.size() - i < b.size() - j;
}

ModelRegistry::ModelRegistry(Options options) : options_(std::move(options)) {
  options_.missing_scans_before_unload = std::max(1u, options_.missing_scans_before_unload);
  default_ = options_.default_model;
  if (!default_.empty()) default_source_ = "flag";
}

void ModelRegistry::read_declared_default() {
  const fs::path file = options_.root / kDefaultModelFile;
  std::error_code error;
  std::string declared;
  // A plain file only: a link could point anywhere, a FIFO would block the scan.
  if (fs::is_regular_file(fs::symlink_status(file, error))) {
    std::ifstream in(file, std::ios::binary);
    char text[kMaxDefaultModelFileBytes + 1] = {};
    in.read(text, sizeof text);
    const std::size_t size = static_cast<std::size_t>(in.gcount());
    declared.assign(text, size);
    declared = declared.substr(0, declared.find_first_of("\r\n"));
    while (!declared.empty() && std::isspace(static_cast<unsigned char>(declared.back())))
      declared.pop_back();
    const bool plain = std::all_of(declared.begin(), declared.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
    });
    if (size > kMaxDefaultModelFileBytes || !plain || declared.empty() || declared[0] == '.') {
      const std::string raw(text, size);
      if (raw != ignored_default_text_)  // once per content, not at every scan
        ops::log_warn("default_model_file_ignored")
            .kv("path", user_text(file.string()))
            .kv("reason", "not one line naming a model (letters, digits, - _ .; at most " +
                              std::to_string(kMaxDefaultModelFileBytes) + " bytes)");
      ignored_default_text_ = raw;
      declared.clear();
    }
  }
  std::lock_guard lock(mutex_);
  declared_default_ = declared;
}

std::map<ModelRegistry::Key, ModelRegistry::Found> ModelRegistry::discover(
    std::vector<Refused>& refused) const {
  std::error_code error;
  const fs::path root = fs::canonical(options_.root, error);
  if (error || !fs::is_directory(root, error))
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "model repository '" + options_.root.string() + "' is not a directory");
  std::vector<fs::directory_entry> model_dirs;
  for (fs::directory_iterator it(root, error), end; !error && it != end; it.increment(error))
    model_dirs.push_back(*it);
  if (error)  // an unlisted repository must not look like one whose models all went away
    throw RegistryError(
        RegistryError::Kind::kNotFound,
        "cannot list the model repository '" + options_.root.string() + "': " + error.message());
  // The resolved path when it stays inside the repository; refusals are collected.
  auto inside = [&](const fs::path& path) -> std::optional<fs::path> {
    std::error_code resolve_error;
    fs::path resolved = fs::canonical(path, resolve_error);
    if (resolve_error) return std::nullopt;  // a dangling link, or removed meanwhile: not there
    if (is_within(root, resolved)) return resolved;
    refused.push_back({path.lexically_relative(root).string(), resolved});
    return std::nullopt;
  };
  std::map<Key, Found> found;
  for (const fs::directory_entry& model_entry : model_dirs) {
    if (hidden(model_entry.path())) continue;
    const auto model_dir = inside(model_entry.path());
    if (!model_dir || !fs::is_directory(*model_dir, error)) continue;
    // Listed by the repository's own names, so refusals and paths read as the operator wrote them.
    for (const fs::directory_entry& version_entry : entries_of(model_entry.path())) {
      if (hidden(version_entry.path())) continue;
      const auto version_dir = inside(version_entry.path());
      if (!version_dir || !fs::is_directory(*version_dir, error)) continue;
      std::vector<fs::path> files;
      for (const fs::directory_entry& file : entries_of(version_entry.path()))
        if (file.path().extension() == ".plm" && !hidden(file.path())) files.push_back(file.path());
      std::sort(files.begin(), files.end());
      for (const fs::path& file : files) {  // several files: the first by name (documented)
        const auto resolved = inside(file);
        if (!resolved || !fs::is_regular_file(*resolved, error)) continue;
        Found entry;
        entry.file = *resolved;
        entry.relative = (fs::path(model_entry.path().filename()) /
                          version_entry.path().filename() / file.filename())
                             .string();
        entry.signature.size = fs::file_size(entry.file, error);
        entry.signature.mtime = fs::last_write_time(entry.file, error);
        found[{model_entry.path().filename().string(), version_entry.path().filename().string()}] =
            entry;
        break;
      }
      // No model file: being written, or not a model version.
    }
  }
  return found;
}

void ModelRegistry::note_refused(const std::vector<Refused>& refused, ReloadReport& report) {
  std::set<std::string> now;
  for (const Refused& path : refused) {
    now.insert(path.relative);
    ++report.refused;
    report.errors.push_back(path.relative + ": resolves to " + path.target.string() +
                            ", outside the model repository");
    if (refused_.count(path.relative)) continue;  // logged when first refused
    ops::log_warn("model_path_refused")
        .kv("path", user_text(path.relative))
        .kv("resolves_to", user_text(path.target.string()))
        .kv("reason", "outside the model repository");
  }
  refused_ = std::move(now);
}

std::shared_ptr<const ModelEntry> ModelRegistry::read_entry(const Key& key,
                                                            const Found& found) const {
  const std::string& relative = found.relative;
  const std::string bytes = read_file(found.file);
  auto entry = std::make_shared<ModelEntry>();
  entry->name = key.first;
  entry->version = key.second;
  entry->path = relative;
  entry->model = std::make_shared<const LabelModel>(parse_model(bytes, relative));
  entry->metadata = metadata_of(bytes, key.first, key.second, relative);
  entry->loaded_unix_ms = unix_ms_now();
  entry->signature = found.signature;
  if (entry->model->name != key.first || entry->model->version != key.second)
    ops::log_warn("model_name_mismatch")
        .kv("path", user_text(relative))
        .kv("file_model", user_text(entry->model->name))
        .kv("file_version", user_text(entry->model->version))
        .kv("served_as", user_text(key.first + "/" + key.second));
  return entry;
}

ReloadReport ModelRegistry::rescan() {
  std::lock_guard reload_lock(reload_mutex_);
  return scan_locked();
}

ReloadReport ModelRegistry::reload() {
  std::lock_guard reload_lock(reload_mutex_);
  unloaded_.clear();
  failed_.clear();
  return scan_locked();
}

ReloadReport ModelRegistry::scan_locked() {
  std::vector<Refused> refused;
  const std::map<Key, Found> found = discover(refused);
  read_declared_default();
  ReloadReport report;
  note_refused(refused, report);
  bool changed = false;
  for (const auto& [key, file] : found) {
    if (unloaded_.count(key) || unloaded_.count({key.first, ""})) continue;
    {
      std::lock_guard lock(mutex_);
      auto model = models_.find(key.first);
      if (model != models_.end()) {
        auto version = model->second.find(key.second);
        if (version != model->second.end() && version->second->signature == file.signature)
          continue;  // unchanged
      }
    }
    auto failed = failed_.find(key);
    if (failed != failed_.end() && failed->second == file.signature) continue;
    try {
      std::shared_ptr<const ModelEntry> entry = read_entry(key, file);  // outside the lock
      {
        std::lock_guard lock(mutex_);
        models_[key.first][key.second] = entry;
      }
      failed_.erase(key);
      changed = true;
      ++report.loaded;
      ops::log_info("model_loaded")
          .kv("model", user_text(key.first))
          .kv("version", user_text(key.second))
          .kv("path", user_text(entry->path));
    } catch (const std::exception& e) {
      failed_[key] = file.signature;
      ++report.failed;
      report.errors.push_back(e.what());
      ops::log_error("model_load_failed")
          .kv("model", user_text(key.first))
          .kv("version", user_text(key.second))
          .kv("error", user_text(e.what(), 1000));
    }
  }
  // Versions missing from disk keep serving until they have been missing long enough.
  {
    std::lock_guard lock(mutex_);
    std::map<Key, unsigned> still_missing;
    for (auto model = models_.begin(); model != models_.end();) {
      for (auto version = model->second.begin(); version != model->second.end();) {
        const Key key{model->first, version->first};
        if (found.count(key)) {
          ++version;
          continue;
        }
        const unsigned scans = missing_.count(key) ? missing_.at(key) + 1 : 1;
        if (scans < options_.missing_scans_before_unload) {
          still_missing[key] = scans;
          ++report.missing;
          ops::log_warn("model_missing")
              .kv("model", user_text(key.first))
              .kv("version", user_text(key.second))
              .kv("missing_scans", scans)
              .kv("unload_after", options_.missing_scans_before_unload);
          ++version;
          continue;
        }
        ops::log_info("model_removed")
            .kv("model", user_text(key.first))
            .kv("version", user_text(key.second))
            .kv("missing_scans", scans);
        version = model->second.erase(version);
        changed = true;
        ++report.removed;
      }
      model = model->second.empty() ? models_.erase(model) : std::next(model);
    }
    missing_ = std::move(still_missing);
    const std::string old_default = default_;
    settle_default_locked();
    changed = changed || default_ != old_default;
  }
  if (changed) notify();
  return report;
}

std::shared_ptr<const ModelEntry> ModelRegistry::load(const std::string& model,
                                                      const std::string& version) {
  check_name("model", model);
  if (!version.empty()) check_name("version", version);
  std::lock_guard reload_lock(reload_mutex_);
  std::vector<Refused> refused;
  const std::map<Key, Found> found = discover(refused);
  const Found* file = nullptr;
  std::string chosen = version;
  for (const auto& [key, entry] : found) {
    if (key.first != model) continue;
    if (version.empty() ? (!file || version_less(chosen, key.second)) : key.second == version) {
      file = &entry;
      chosen = key.second;
    }
  }
  if (!file)
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "no model file for model '" + user_text(model) + "'" +
                            version_part(version) + " under " + options_.root.string());
  const Key key{model, chosen};
  std::shared_ptr<const ModelEntry> entry;
  try {
    entry = read_entry(key, *file);
  } catch (const std::exception& e) {
    failed_[key] = file->signature;
    throw RegistryError(RegistryError::Kind::kLoadFailed, e.what());
  }
  {
    std::lock_guard lock(mutex_);
    models_[model][chosen] = entry;
    missing_.erase(key);
    settle_default_locked();
  }
  failed_.erase(key);
  unloaded_.erase(key);
  unloaded_.erase({model, ""});
  ops::log_info("model_loaded")
      .kv("model", user_text(model))
      .kv("version", user_text(chosen))
      .kv("path", user_text(entry->path));
  notify();
  return entry;
}

unsigned ModelRegistry::unload(const std::string& model, const std::string& version) {
  check_name("model", model);
  if (!version.empty()) check_name("version", version);
  std::lock_guard reload_lock(reload_mutex_);
  unsigned removed = 0;
  {
    std::lock_guard lock(mutex_);
    auto found = models_.find(model);
    if (found != models_.end()) {
      if (version.empty()) {
        removed = unsigned(found->second.size());
        models_.erase(found);
      } else {
        removed = unsigned(found->second.erase(version));
        if (found->second.empty()) models_.erase(found);
      }
    }
    if (removed == 0)
      throw RegistryError(
          RegistryError::Kind::kNotFound,
          "model '" + user_text(model) + "'" + version_part(version) + " is not loaded");
    settle_default_locked();
  }
  unloaded_.insert({model, version});
  ops::log_info("model_unloaded")
      .kv("model", user_text(model))
      .kv("version", user_text(version))
      .kv("versions", removed);
  notify();
  return removed;
}

void ModelRegistry::notify() const {
  if (observer_) observer_();
}

std::shared_ptr<const ModelEntry> ModelRegistry::served_locked(const std::string& model,
                                                               const Versions& versions) const {
  auto pin = options_.pins.find(model);
  if (pin != options_.pins.end()) {
    auto pinned = versions.find(pin->second);
    if (pinned != versions.end()) return pinned->second;
  }
  return versions.rbegin()->second;  // the latest
}

void ModelRegistry::settle_default_locked() {
  if (!options_.default_model.empty()) return;  // named by the operator: never moves
  if (!declared_default_.empty()) {             // the repository's own word, followed as it changes
    default_ = declared_default_;
    default_source_ = "repository";
    return;
  }
  if (default_source_ == "repository") default_.clear(), default_source_.clear();
  // The only model becomes the default and stays it when others appear, so requests naming no
  // model keep working. When it is gone and several remain, there is no safe guess: requests
  // naming no model are refused, naming the default, until it returns or only one is left.
  if (models_.size() == 1) default_ = models_.begin()->first, default_source_ = "only model";
}

std::string ModelRegistry::describe_loaded_locked() const {
  if (models_.empty()) return "no model is loaded";
  std::string text = "loaded: ";
  bool first_model = true;
  for (const auto& [name, versions] : models_) {
    if (!first_model) text += ", ";
    first_model = false;
    text += user_text(name);
    text += " (";
    bool first_version = true;
    for (const auto& [version, entry] : versions) {
      if (!first_version) text += ' ';
      first_version = false;
      text += user_text(version);
    }
    text += ')';
  }
  return user_text(text, 2000);  // a repository of thousands of models stays one readable line
}

std::shared_ptr<const ModelEntry> ModelRegistry::resolve(const std::string& model,
                                                         const std::string& version) const {
  std::lock_guard lock(mutex_);
  if (model.empty() && default_.empty())
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "the request names no model and the server has no default model "
                        "(--default-model, or the repository's default_model file); " +
                            describe_loaded_locked());
  const std::string& name = model.empty() ? default_ : model;
  auto found = models_.find(name);
  if (found == models_.end())
    throw RegistryError(RegistryError::Kind::kNotFound,
                        std::string(model.empty() ? "the default model '" : "model '") +
                            user_text(name) + "' is not loaded; " + describe_loaded_locked());
  if (version.empty()) return served_locked(name, found->second);
  auto exact = found->second.find(version);
  if (exact == found->second.end())
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "model '" + user_text(name) + "' has no version '" + user_text(version) +
                            "'; " + describe_loaded_locked());
  return exact->second;
}

std::vector<ServedModel> ModelRegistry::list() const {
  std::lock_guard lock(mutex_);
  std::vector<ServedModel> out;
  for (const auto& [name, versions] : models_) {
    ServedModel served;
    served.name = name;
    served.served = served_locked(name, versions);
    for (const auto& [version, entry] : versions) served.versions.push_back(version);
    served.is_default = name == default_;
    out.push_back(std::move(served));
  }
  return out;
}

std::size_t ModelRegistry::loaded_versions() const {
  std::lock_guard lock(mutex_);
  std::size_t count = 0;
  for (const auto& [name, versions] : models_) count += versions.size();
  return count;
}

std::string ModelRegistry::default_model() const {
  std::lock_guard lock(mutex_);
  return default_;
}

std::string ModelRegistry::default_source() const {
  std::lock_guard lock(mutex_);
  return default_.empty() ? std::string() : default_source_;
}

std::string ModelRegistry::configuration_problem() const {
  std::lock_guard lock(mutex_);
  const std::string& wanted = options_.default_model;
  if (!wanted.empty() && !models_.count(wanted))
    return "--default-model '" + user_text(wanted) + "' is not a loaded model; " +
           describe_loaded_locked();
  for (const auto& [model, version] : options_.pins) {
    const std::string flag = "--pin " + user_text(model) + "=" + user_text(version) + ": ";
    auto found = models_.find(model);
    if (found == models_.end())
      return flag + "model '" + user_text(model) + "' is not loaded; " + describe_loaded_locked();
    if (!found->second.count(version))
      return flag + "model '" + user_text(model) + "' has no version '" + user_text(version) +
             "'; " + describe_loaded_locked();
  }
  return {};
}

}  // namespace primlabel::service

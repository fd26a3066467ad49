#include "model_registry.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <sstream>

#include "logging.hpp"
#include "primlabel/v1/model.pb.h"

namespace primlabel::server {

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
                        "invalid " + what + " name '" + name + "'");
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

ModelRegistry::ModelRegistry(Options options) : options_(std::move(options)) {}

std::map<ModelRegistry::Key, ModelRegistry::Found> ModelRegistry::discover() const {
  std::error_code error;
  if (!fs::is_directory(options_.root, error))
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "model repository '" + options_.root.string() + "' is not a directory");
  std::map<Key, Found> found;
  for (const fs::directory_entry& model_dir : fs::directory_iterator(options_.root, error)) {
    if (!model_dir.is_directory(error) || hidden(model_dir.path())) continue;
    for (const fs::directory_entry& version_dir : fs::directory_iterator(model_dir.path(), error)) {
      if (!version_dir.is_directory(error) || hidden(version_dir.path())) continue;
      std::vector<fs::path> files;
      for (const fs::directory_entry& file : fs::directory_iterator(version_dir.path(), error))
        if (file.is_regular_file(error) && file.path().extension() == ".plm" &&
            !hidden(file.path()))
          files.push_back(file.path());
      if (files.empty()) continue;  // being written, or not a model version
      std::sort(files.begin(), files.end());
      Found entry;
      entry.file = files.front();  // several files: the first by name (documented)
      entry.signature.size = fs::file_size(entry.file, error);
      entry.signature.mtime = fs::last_write_time(entry.file, error);
      found[{model_dir.path().filename().string(), version_dir.path().filename().string()}] = entry;
    }
  }
  return found;
}

std::shared_ptr<const ModelEntry> ModelRegistry::read_entry(const Key& key,
                                                            const Found& found) const {
  const std::string relative = fs::relative(found.file, options_.root).string();
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
    log_warn("model_name_mismatch")
        .kv("path", relative)
        .kv("file_model", entry->model->name)
        .kv("file_version", entry->model->version)
        .kv("served_as", key.first + "/" + key.second);
  return entry;
}

ReloadReport ModelRegistry::rescan() {
  std::lock_guard reload_lock(reload_mutex_);
  const std::map<Key, Found> found = discover();
  ReloadReport report;
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
      ++report.loaded;
      log_info("model_loaded")
          .kv("model", key.first)
          .kv("version", key.second)
          .kv("path", entry->path);
    } catch (const std::exception& e) {
      failed_[key] = file.signature;
      ++report.failed;
      report.errors.push_back(e.what());
      log_error("model_load_failed")
          .kv("model", key.first)
          .kv("version", key.second)
          .kv("error", e.what());
    }
  }
  // Versions whose directory went away stop being served.
  std::lock_guard lock(mutex_);
  for (auto model = models_.begin(); model != models_.end();) {
    for (auto version = model->second.begin(); version != model->second.end();) {
      if (found.count({model->first, version->first})) {
        ++version;
        continue;
      }
      log_info("model_removed").kv("model", model->first).kv("version", version->first);
      version = model->second.erase(version);
      ++report.removed;
    }
    model = model->second.empty() ? models_.erase(model) : std::next(model);
  }
  return report;
}

std::shared_ptr<const ModelEntry> ModelRegistry::load(const std::string& model,
                                                      const std::string& version) {
  check_name("model", model);
  if (!version.empty()) check_name("version", version);
  std::lock_guard reload_lock(reload_mutex_);
  const std::map<Key, Found> found = discover();
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
                        "no model file for model '" + model + "'" +
                            (version.empty() ? "" : " version '" + version + "'") + " under " +
                            options_.root.string());
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
  }
  failed_.erase(key);
  unloaded_.erase(key);
  unloaded_.erase({model, ""});
  log_info("model_loaded").kv("model", model).kv("version", chosen).kv("path", entry->path);
  return entry;
}

unsigned ModelRegistry::unload(const std::string& model, const std::string& version) {
  check_name("model", model);
  if (!version.empty()) check_name("version", version);
  std::lock_guard reload_lock(reload_mutex_);
  std::lock_guard lock(mutex_);
  auto found = models_.find(model);
  unsigned removed = 0;
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
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "model '" + model + "'" +
                            (version.empty() ? "" : " version '" + version + "'") +
                            " is not loaded");
  unloaded_.insert({model, version});
  log_info("model_unloaded").kv("model", model).kv("version", version).kv("versions", removed);
  return removed;
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

std::string ModelRegistry::default_model_locked() const {
  if (!options_.default_model.empty()) return options_.default_model;
  if (models_.size() == 1) return models_.begin()->first;
  return {};
}

std::string ModelRegistry::describe_loaded_locked() const {
  if (models_.empty()) return "no model is loaded";
  std::string text = "loaded: ";
  bool first_model = true;
  for (const auto& [name, versions] : models_) {
    text += (first_model ? "" : ", ") + name + " (";
    first_model = false;
    bool first_version = true;
    for (const auto& [version, entry] : versions) {
      text += (first_version ? "" : " ") + version;
      first_version = false;
    }
    text += ")";
  }
  return text;
}

std::shared_ptr<const ModelEntry> ModelRegistry::resolve(const std::string& model,
                                                         const std::string& version) const {
  std::lock_guard lock(mutex_);
  const std::string name = model.empty() ? default_model_locked() : model;
  if (name.empty())
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "the request names no model and the server has no default model; " +
                            describe_loaded_locked());
  auto found = models_.find(name);
  if (found == models_.end())
    throw RegistryError(RegistryError::Kind::kNotFound,
                        "model '" + name + "' is not loaded; " + describe_loaded_locked());
  if (version.empty()) return served_locked(name, found->second);
  auto exact = found->second.find(version);
  if (exact == found->second.end())
    throw RegistryError(
        RegistryError::Kind::kNotFound,
        "model '" + name + "' has no version '" + version + "'; " + describe_loaded_locked());
  return exact->second;
}

std::vector<ServedModel> ModelRegistry::list() const {
  std::lock_guard lock(mutex_);
  const std::string default_name = default_model_locked();
  std::vector<ServedModel> out;
  for (const auto& [name, versions] : models_) {
    ServedModel served;
    served.name = name;
    served.served = served_locked(name, versions);
    for (const auto& [version, entry] : versions) served.versions.push_back(version);
    served.is_default = name == default_name;
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
  return default_model_locked();
}

}  // namespace primlabel::server

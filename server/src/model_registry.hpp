#pragma once
// The models the server serves, from a repository directory laid out as
// <root>/<model>/<version>/<file>.plm (one model file per version directory).
//
// Every version found is loaded; a model is served at its pinned version or else its latest
// (versions compare like file names, digit runs by numeric value: "2" < "10"). Loading reads and
// checks a file completely before the new entry replaces the old one, so a request that took an
// entry (a shared_ptr) keeps using it unchanged, and a file that fails to load leaves the old
// version serving. Thread-safe.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/model/label_model.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::server {

// Size and modification time: a version is reloaded when its file's signature changes.
struct FileSignature {
  std::uintmax_t size = 0;
  std::filesystem::file_time_type mtime{};
  bool operator==(const FileSignature&) const = default;
};

struct ModelEntry {
  std::string name, version;
  std::string path;  // of the file, relative to the repository root
  std::shared_ptr<const LabelModel> model;
  v1::ModelMetadata metadata;  // everything but the weights, as the file states it
  std::int64_t loaded_unix_ms = 0;
  FileSignature signature;
};

// Why a registry operation failed.
class RegistryError : public std::runtime_error {
 public:
  enum class Kind { kNotFound, kInvalidArgument, kLoadFailed };
  RegistryError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct ReloadReport {
  unsigned loaded = 0;              // versions newly loaded or replaced
  unsigned failed = 0;              // versions that failed to load (old ones keep serving)
  unsigned removed = 0;             // versions whose directory disappeared
  std::vector<std::string> errors;  // "path: reason"
};

// One model as ListModels shows it.
struct ServedModel {
  std::string name;
  std::shared_ptr<const ModelEntry> served;  // pinned or latest version
  std::vector<std::string> versions;         // loaded, oldest first
  bool is_default = false;
};

// "2" < "10" < "10a"; otherwise byte order.
bool version_less(const std::string& a, const std::string& b);
struct VersionLess {
  bool operator()(const std::string& a, const std::string& b) const { return version_less(a, b); }
};

class ModelRegistry {
 public:
  struct Options {
    std::filesystem::path root;
    std::string default_model;                // empty: the only model, if there is one
    std::map<std::string, std::string> pins;  // model -> version served by default
  };
  explicit ModelRegistry(Options options);

  // Loads new and changed versions and drops versions whose directory went away. A version that
  // failed to load is not retried until its file changes. Versions unloaded by unload() are
  // skipped until load() brings them back. Throws RegistryError(kNotFound) when the root is not
  // a readable directory.
  ReloadReport rescan();

  // Loads (or reloads) one version from the repository; an empty version means the latest on
  // disk. Throws RegistryError.
  std::shared_ptr<const ModelEntry> load(const std::string& model, const std::string& version);

  // Stops serving one version, or every version when version is empty; returns how many.
  // Throws RegistryError(kNotFound) when nothing matched.
  unsigned unload(const std::string& model, const std::string& version);

  // The entry a request for (model, version) gets: empty model = the default model, empty
  // version = the pinned or latest. Throws RegistryError(kNotFound) naming what is loaded.
  std::shared_ptr<const ModelEntry> resolve(const std::string& model,
                                            const std::string& version) const;

  std::vector<ServedModel> list() const;
  std::size_t loaded_versions() const;
  std::string default_model() const;
  const std::filesystem::path& root() const { return options_.root; }

 private:
  struct Found {
    std::filesystem::path file;
    FileSignature signature;
  };
  using Key = std::pair<std::string, std::string>;  // model, version
  using Versions = std::map<std::string, std::shared_ptr<const ModelEntry>, VersionLess>;

  std::map<Key, Found> discover() const;  // what is on disk now
  std::shared_ptr<const ModelEntry> read_entry(const Key& key, const Found& found) const;
  std::shared_ptr<const ModelEntry> served_locked(const std::string& model,
                                                  const Versions& versions) const;
  std::string default_model_locked() const;
  std::string describe_loaded_locked() const;

  Options options_;
  std::mutex reload_mutex_;   // one rescan / load / unload at a time
  mutable std::mutex mutex_;  // guards models_ (held only to look up or swap)
  std::map<std::string, Versions> models_;
  std::map<Key, FileSignature> failed_;  // files that failed to load, until they change
  std::set<Key> unloaded_;               // (model, "") = every version of the model
};

}  // namespace primlabel::server

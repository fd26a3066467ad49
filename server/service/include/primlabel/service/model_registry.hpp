#pragma once
// The models the server serves, from a repository directory laid out as
// <root>/<model>/<version>/<file>.plm (one model file per version directory).
//
// Every version found is loaded; a model is served at its pinned version or else its latest
// (versions compare like file names, digit runs by numeric value: "2" < "10"). Loading reads and
// checks a file completely before the new entry replaces the old one, so a request that took an
// entry (a shared_ptr) keeps using it unchanged, and a file that fails to load leaves the old
// version serving. Thread-safe.
//
// Last known good: a loaded version whose directory is missing stays served until it has been
// missing at `missing_scans_before_unload` consecutive scans (a directory moved away and back,
// or a repository being synced, must not take the model down), or until unload().
// Paths are resolved: a model directory, version directory or model file that resolves outside
// the repository (a symlink to elsewhere) is refused and logged, never read.
// The default model, for requests whose cloud no model's domain decides: Options::default_model
// (--default-model) if given; else the model the repository declares in the file
// <root>/default_model (one line, read at every scan); else the only model, which stays the
// default when other models appear.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/model/label_model.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

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
  unsigned removed = 0;             // versions whose directory disappeared (for long enough)
  unsigned missing = 0;             // versions missing from disk but still served (last known good)
  unsigned refused = 0;             // paths that resolve outside the repository
  std::vector<std::string> errors;  // "path: reason"
};

// One model as ListModels shows it.
struct ServedModel {
  std::string name;
  std::shared_ptr<const ModelEntry> served;  // pinned or latest version
  std::vector<std::string> versions;         // loaded, oldest first
  bool is_default = false;
};

// The file at a repository's root that names its default model (one line), and its size bound.
inline constexpr const char* kDefaultModelFile = "default_model";
inline constexpr std::size_t kMaxDefaultModelFileBytes = 256;

// "2" < "10" < "10a"; otherwise byte order.
bool version_less(const std::string& a, const std::string& b);
struct VersionLess {
  bool operator()(const std::string& a, const std::string& b) const { return version_less(a, b); }
};

class ModelRegistry {
 public:
  struct Options {
    std::filesystem::path root;
    std::string default_model;                 // empty: the only model, if there is one
    std::map<std::string, std::string> pins;   // model -> version served by default
    unsigned missing_scans_before_unload = 3;  // consecutive scans; 1 = at once
  };
  explicit ModelRegistry(Options options);

  // Called after every change of what is served (a version loaded, replaced or removed, the
  // default moved), with no registry lock but the one that orders changes held: the callback may
  // read the registry (list(), resolve(), ...) but must not change it. Set it before the
  // registry is shared between threads.
  void set_observer(std::function<void()> observer) { observer_ = std::move(observer); }

  // The periodic scan: loads new and changed versions and drops versions whose directory has
  // been missing at missing_scans_before_unload consecutive scans. A version that failed to load
  // is not retried until its file changes. Versions unloaded by unload() are skipped until
  // load() or reload() brings them back. Throws RegistryError(kNotFound) when the root is not a
  // readable directory.
  ReloadReport rescan();

  // An explicit reload (ReloadModels): lifts every unload() and retries files that failed to
  // load, then scans as rescan() does.
  ReloadReport reload();

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
  std::string default_model() const;  // empty: none
  // Where the default comes from: "flag", "repository" (<root>/default_model), "only model" or
  // "" when there is none.
  std::string default_source() const;
  const std::filesystem::path& root() const { return options_.root; }

  // What is wrong with Options::default_model and pins given what is loaded now (a model or
  // version that is not loaded), as one line naming the flag; empty when nothing is.
  std::string configuration_problem() const;

 private:
  struct Found {
    std::filesystem::path file;  // canonical: the file that is read
    std::string relative;        // <model>/<version>/<file>, as the repository names it
    FileSignature signature;
  };
  struct Refused {
    std::string relative;  // as the repository names it
    std::filesystem::path target;
  };
  using Key = std::pair<std::string, std::string>;  // model, version
  using Versions = std::map<std::string, std::shared_ptr<const ModelEntry>, VersionLess>;

  // What is on disk now; paths leading outside the repository go to `refused`.
  std::map<Key, Found> discover(std::vector<Refused>& refused) const;
  ReloadReport scan_locked();  // with reload_mutex_ held
  void note_refused(const std::vector<Refused>& refused, ReloadReport& report);
  std::shared_ptr<const ModelEntry> read_entry(const Key& key, const Found& found) const;
  std::shared_ptr<const ModelEntry> served_locked(const std::string& model,
                                                  const Versions& versions) const;
  void settle_default_locked();
  // Reads <root>/default_model into declared_default_ (a missing file declares none; a file that
  // is unreadable, too long or not a model name is logged and declares none).
  void read_declared_default();
  std::string describe_loaded_locked() const;
  void notify() const;

  Options options_;
  std::function<void()> observer_;
  std::mutex reload_mutex_;   // one rescan / load / unload at a time
  mutable std::mutex mutex_;  // guards models_ and default_ (held only to look up or swap)
  std::map<std::string, Versions> models_;
  std::string default_;                  // the sticky default model; empty: none
  std::string default_source_;           // see default_source()
  std::string declared_default_;         // <root>/default_model at the last scan; empty: none
  std::string ignored_default_text_;     // the last default_model content refused (logged once)
  std::map<Key, FileSignature> failed_;  // files that failed to load, until they change
  std::set<Key> unloaded_;               // (model, "") = every version of the model
  std::map<Key, unsigned> missing_;      // loaded versions missing from disk: consecutive scans
  std::set<std::string> refused_;        // refused at the last scan (logged once)
};

}  // namespace primlabel::service

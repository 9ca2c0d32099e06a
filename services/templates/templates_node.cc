#include "services/templates/templates_node.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "common/persistence/state_file.h"
#include "services/camera/image_message.h"
#include "services/templates/template_journal.h"
#include "services/templates/template_library.h"
#include "services/templates/view_match_message.h"

namespace rslam::templates {
namespace {

constexpr const char* kStateKind = "rslam.templates.TemplateLibraryState";
constexpr uint32_t kStateVersion = 1;

std::string JournalPathFor(const std::string& state_path) {
  const std::string suffix = ".pb";
  const std::string stem = state_path.ends_with(suffix) ? state_path.substr(0, state_path.size() - suffix.size())
                                                        : state_path;
  return stem + ".journal";
}

// The saved library: the state file, then the journal's templates after it.
TemplateLibrary LoadLibrary(const std::string& state_path, const std::string& journal_path,
                            const TemplateConfig& config, uint64_t& journal_valid_bytes) {
  proto::TemplateLibraryState state;
  bool have_state = false;
  if (std::filesystem::exists(state_path)) {
    ReadStateFile(state_path, kStateKind, kStateVersion, state);
    have_state = true;
  }
  TemplateJournal::Contents journal = TemplateJournal::Read(journal_path);
  journal_valid_bytes = journal.valid_bytes;
  if (journal.torn_tail) spdlog::warn("{}: dropped a torn last record (never published)", journal_path);
  std::size_t replayed = 0;
  for (proto::Template& t : journal.templates) {
    const auto next = static_cast<uint32_t>(state.templates_size());
    if (t.id() < next) continue;  // already in the state file (saved after it was journaled)
    if (t.id() > next)
      throw StateFileError(journal_path + ": journal skips from template " + std::to_string(next) + " to " +
                           std::to_string(t.id()));
    if (!have_state) {
      // A journal without a state file: the library starts from the config's empty state.
      state = TemplateLibrary(config).ToProto();
      have_state = true;
    }
    *state.add_templates() = std::move(t);
    ++replayed;
  }
  if (!have_state) return TemplateLibrary(config);
  TemplateLibrary library = TemplateLibrary::FromProto(state, config);
  spdlog::info("loaded {} templates ({} from {})", library.size(), replayed, journal_path);
  return library;
}

}  // namespace

class TemplatesNode::Impl {
 public:
  Impl(ServiceContext& context, const Config& config)
      : context_(context),
        config_(config),
        state_path_(context.StateFilePath()),
        library_(Load(context, config)) {
    if (!state_path_.empty()) {
      // Start from a state file that holds everything (also after --fresh: an old file must not
      // meet a new journal), then an empty journal.
      SaveLocked();
    }
  }

  void Start(const std::shared_ptr<Impl>& self, std::vector<std::shared_ptr<void>>& subscriptions) {
    publisher_ = context_.Advertise(bus::topics::kTemplatesView);
    std::weak_ptr<Impl> weak = self;
    subscriptions.push_back(
        context_.Subscribe<msg::Image>(bus::topics::kCameraImage, [weak](const msg::Image& image) {
          if (auto impl = weak.lock()) impl->OnImage(image);
        }));
  }

  void Tick() {
    std::lock_guard lock(mutex_);
    if (stopped_ || state_path_.empty() || learnt_since_save_ == 0) return;
    if (std::chrono::steady_clock::now() - last_save_ <
        std::chrono::duration<double>(context_.runtime().state_save_period_s))
      return;
    SaveOrLog();
  }

  void Stop() {
    std::lock_guard lock(mutex_);
    stopped_ = true;
    if (!state_path_.empty() && learnt_since_save_ > 0) SaveOrLog();
  }

 private:
  TemplateLibrary Load(ServiceContext& context, const Config& config) {
    const std::string state_path = context.StateFilePath();
    if (state_path.empty()) return TemplateLibrary(config.library);
    const std::string journal_path = JournalPathFor(state_path);
    uint64_t valid_bytes = 0;
    std::optional<TemplateLibrary> library;
    if (context.runtime().fresh) {
      spdlog::info("--fresh: starting with no templates");
      library.emplace(config.library);
    } else {
      library.emplace(LoadLibrary(state_path, journal_path, config.library, valid_bytes));
    }
    journal_ = std::make_unique<TemplateJournal>(journal_path, valid_bytes, config.sync_journal);
    return std::move(*library);
  }

  // Writes the whole library, then clears the journal (its templates are now in the file).
  void SaveLocked() {
    WriteStateFile(state_path_, kStateKind, kStateVersion, library_.ToProto());
    journal_->Clear();
    learnt_since_save_ = 0;
    last_save_ = std::chrono::steady_clock::now();
  }

  void SaveOrLog() {
    try {
      SaveLocked();
    } catch (const std::exception& e) {
      // The journal still holds every template: nothing is lost, the next save tries again.
      spdlog::error("saving {}: {}", state_path_, e.what());
    }
  }

  void OnImage(const msg::Image& image) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    const std::string problem = camera::ImageMessageProblem(image, static_cast<uint64_t>(config_.max_pixels));
    if (!problem.empty()) return context_.Reject("malformed_image", problem);
    ViewMatch match;
    try {
      match = library_.MatchOrLearn(camera::GreyImage(image));
    } catch (const std::invalid_argument& e) {
      return context_.Reject("unusable_image", e.what());
    }
    if (match.is_new && journal_) {
      // Durable before anyone hears of the id: a restart must never give it to another view.
      try {
        journal_->Append(library_.TemplateToProto(match.template_id));
      } catch (const std::exception& e) {
        // The library now holds a template the disk does not: going on would publish an id a
        // restart could give to another view. Stop; a supervisor restarts from the saved state.
        spdlog::critical("{}; exiting without publishing template {}", e.what(), match.template_id);
        spdlog::default_logger()->flush();
        std::_Exit(1);
      }
      ++learnt_since_save_;
    }
    const msg::ViewTemplate out = ToViewMessage(image.header, match, static_cast<uint32_t>(library_.size()));
    try {
      publisher_->Publish(out);
    } catch (const bus::BusError& e) {
      // A reliable reader blocked beyond the preset's limit misses this view; the template is
      // kept (journaled) and the service goes on.
      context_.Reject("view_not_delivered", e.what());
    }
    context_.SetLastFrame(image.header.frame_seq, image.header.stamp_ns);
  }

  ServiceContext& context_;
  const Config config_;
  const std::string state_path_;
  std::unique_ptr<TemplateJournal> journal_;  // set by Load (before library_ is initialised)
  std::mutex mutex_;
  bool stopped_ = false;
  TemplateLibrary library_;
  uint64_t learnt_since_save_ = 0;
  std::chrono::steady_clock::time_point last_save_ = std::chrono::steady_clock::now();
  std::shared_ptr<bus::Publisher<msg::ViewTemplate>> publisher_;
};

TemplatesNode::TemplatesNode(ServiceContext& context, const Config& config)
    : impl_(std::make_shared<Impl>(context, config)) {
  impl_->Start(impl_, subscriptions_);
}

TemplatesNode::~TemplatesNode() {
  subscriptions_.clear();  // joins the callback thread: no view is learnt after the final save
  impl_->Stop();
}

void TemplatesNode::Tick() { impl_->Tick(); }

}  // namespace rslam::templates

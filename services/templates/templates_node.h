#pragma once
// The templates (local view) service on the bus.
//
// In:  camera/image (msg::Image, mono8 or bgr8 -> grey).
// Out: templates/view (msg::ViewTemplate, header copied from the frame): the matched or new
//      template id, relative angle, difference (an empty library's +infinity is sent as
//      kNoTemplateDifference: messages with non-finite numbers are refused downstream) and the
//      template count.
//
// State (template ids are referenced by the pose cells, so none may be lost or reused):
// <state_dir>/templates.pb holds the whole library (written at start, every
// state_save_period_s when something was learnt, and on shutdown); every template learnt since
// is appended to <state_dir>/templates.journal and synced before its view is published. At start
// the state file and then the journal are loaded (a torn last journal record is dropped: its
// view was never published). A corrupt state file or journal refuses the start (exit 1);
// --fresh starts empty. Malformed images and images the library cannot use are counted as
// rejected and dropped.

#include <memory>
#include <vector>

#include "common/node/service_context.h"
#include "services/templates/templates_node_config.h"

namespace rslam::templates {

class TemplatesNode {
 public:
  using Config = TemplatesNodeConfig;

  // Throws StateFileError / std::invalid_argument for a corrupt or mismatched state.
  TemplatesNode(ServiceContext& context, const Config& config);
  ~TemplatesNode();  // saves the state
  TemplatesNode(const TemplatesNode&) = delete;
  TemplatesNode& operator=(const TemplatesNode&) = delete;

  // Periodic state save.
  void Tick();

  // Shared with the subscriber's callback thread.
  class Impl;

 private:
  std::shared_ptr<Impl> impl_;
  // The node owns its subscription (the context keeps none): cleared first on destruction.
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::templates

#pragma once
// Configuration of the templates service (YAML section `templates`): the template library keys
// (TemplateConfig, so deploy/presets/*.yaml work as they are) plus the node's own.

#include <cstdint>

#include "common/config/config_error.h"
#include "services/templates/template_config.h"

namespace rslam::templates {

struct TemplatesNodeConfig {
  TemplateConfig library;
  bool sync_journal = true;         // fsync each journaled template before its view is published
  int64_t max_pixels = 16'000'000;  // larger images are rejected

  template <class V>
  void VisitFields(V& v) {
    library.VisitFields(v);
    v("sync_journal", sync_journal,
      "fsync each new template to the journal before publishing it (off: faster, a power cut may lose templates)");
    v("max_pixels", max_pixels, "images with more pixels are rejected");
  }

  void Validate() const {
    library.Validate();
    Require(max_pixels >= 1, "max_pixels", "must be >= 1");
  }
};

}  // namespace rslam::templates

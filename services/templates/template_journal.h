#pragma once
// Write-ahead journal of the templates learnt since the last state file. Template ids are
// referenced by the pose cells, so a template that was published must survive a SIGKILL: the
// node appends the new template here (and syncs it to disk) before publishing its view, and
// writes the full state file only now and then (after which the journal is cleared).
//
// File: a sequence of records, each
//   u32 magic 0x4A545352 ("RSTJ"), u32 payload length, u32 CRC-32 of the payload, payload
// (a serialized rslam.templates.proto.Template), little-endian. A crash mid-append leaves a torn
// last record: it is dropped on reading (it was never published). A bad record followed by
// further data is corruption and refuses the whole journal.

#include <cstdint>
#include <string>
#include <vector>

#include "services/templates/proto/template_library.pb.h"

namespace rslam::templates {

class TemplateJournal {
 public:
  struct Contents {
    std::vector<proto::Template> templates;  // in file order
    uint64_t valid_bytes = 0;                // length of the intact prefix
    bool torn_tail = false;                  // a partial last record was found (and dropped)
  };

  // Reads the journal at path (a missing file is an empty journal). Throws StateFileError
  // naming the path for corruption before the last record.
  static Contents Read(const std::string& path);

  // Opens path for appending, cutting it to valid_bytes (dropping a torn tail). sync: fsync each
  // appended record before Append returns.
  TemplateJournal(std::string path, uint64_t valid_bytes, bool sync);
  ~TemplateJournal();
  TemplateJournal(const TemplateJournal&) = delete;
  TemplateJournal& operator=(const TemplateJournal&) = delete;

  // Appends one record; durable on return when sync. Throws StateFileError on I/O errors.
  void Append(const proto::Template& t);
  // Empties the journal (after the state file holding its templates was written).
  void Clear();
  const std::string& path() const { return path_; }

 private:
  const std::string path_;
  const bool sync_;
  int fd_ = -1;
  std::string buffer_;
};

}  // namespace rslam::templates

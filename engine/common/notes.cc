#include "engine/common/notes.h"

#include <utility>

namespace gesweep {
namespace {

std::function<void(const std::string&)>& Handler() {
  static std::function<void(const std::string&)> handler;
  return handler;
}

}  // namespace

void SetNoteHandler(std::function<void(const std::string&)> handler) { Handler() = std::move(handler); }

void SendNote(const std::string& note) {
  if (Handler()) Handler()(note);
}

}  // namespace gesweep

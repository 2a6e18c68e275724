#pragma once
/// Notes to the person: something accepted that they should know of (an older name of a run
/// parameter, docs/sweep.md "Renamed parameters"). Nothing below the front ends prints: the engine
/// sends a note here, and the front end's handler shows it (the command line and the Python module:
/// one line "gesweep: note: ..." on stderr, once per text). Without a handler a note is dropped.

#include <functional>
#include <string>

namespace gesweep {

/// Sets the function that shows notes (empty: none is shown).
void SetNoteHandler(std::function<void(const std::string&)> handler);

/// Passes `note` (one line, with its source) to the handler.
void SendNote(const std::string& note);

}  // namespace gesweep

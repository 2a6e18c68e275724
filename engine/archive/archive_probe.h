#pragma once
/// Damaged archives that break libhdf5 itself (docs/reliability.md, "11.4 Damaged archives"): on some
/// damaged files libhdf5 1.10.8 loops for ever, reads out of bounds or frees a bad pointer while it
/// decodes them (tests/fuzz/hdf5_defects), which no check made through libhdf5 can prevent. So every
/// archive a person names is first decoded in a child process with a deadline: the child (fork)
/// makes the whole open-time check of ArchiveReader::Open and reads everything libhdf5 decodes from
/// metadata (every attribute of every object, every variable-length dataset: the global heap),
/// then reports that it finished; only then does the process itself open the file. A child that dies
/// by a signal, exits without reporting, or overruns the deadline is one InputError line (exit 2)
/// naming the file, and nothing of the file is touched.

#include <exception>
#include <filesystem>
#include <functional>
#include <string>

namespace gesweep::archive {

/// What became of a probe run in a child process.
struct ProbeOutcome {
  enum class Kind {
    kFinished,   ///< the probe returned
    kThrew,      ///< the probe threw `error` (an InputError, RequestError or ArchiveError, rebuilt)
    kSignal,     ///< the child died by a signal (`signal`)
    kExited,     ///< the child exited without finishing (e.g. AddressSanitizer's exit code 1)
    kTimedOut,   ///< the deadline passed; the child was killed
    kNoProcess,  ///< fork failed: the probe was not run
  } kind = Kind::kFinished;
  int signal = 0;
  int exit_code = 0;
  std::exception_ptr error;  ///< kThrew: the probe's exception, rebuilt in this process
  std::string remedy;        ///< kThrew by a RequestError: its remedy
};

/// Runs `probe` in a forked child process with its standard output and error sent to /dev/null, no
/// core dump, SIGINT/SIGTERM/SIGHUP ignored (the parent handles them; the deadline bounds the child),
/// killed when the parent dies, and waits at most `deadline_s` seconds of wall time for it. The
/// child leaves through _exit: no atexit handler, no stdio flush, no HDF5 clean-up of files the
/// parent holds. An exception thrown by `probe` is sent back and rebuilt (InputError, RequestError
/// with its remedy, ArchiveError; anything else as an ArchiveError with its what()).
ProbeOutcome RunInChild(const std::function<void()>& probe, double deadline_s);

/// True inside a probe's child (a nested ArchiveReader::Open there runs directly).
bool InProbeChild();

/// The deadline of the archive check, in seconds of wall time: 3 by default; GESWEEP_ARCHIVE_CHECK_S
/// (a number in [0.1, 3600]) sets it (e.g. for a very slow machine); GESWEEP_ARCHIVE_CHECK_S=0 turns
/// the check off (the open then runs in-process, unguarded).
double ArchiveCheckDeadline();

/// The guard ArchiveReader::Open puts before libhdf5 decodes an archive: `probe` (the open-time
/// check and the metadata reads) runs in a child with ArchiveCheckDeadline(); when libhdf5 crashed or
/// hung in it, throws InputError(shown, "", "", "libhdf5 ... while decoding the file: a damaged
/// archive"); when the probe threw, throws that error (the file is not decoded again in this process),
/// unless it is a RequestError whose remedy is `pass_remedy` (non-empty). Returns normally when the
/// probe returned, inside a probe's child, when the check is off, or when no process could be made.
void GuardArchiveDecode(const std::string& shown, const std::function<void()>& probe,
                        const std::string& pass_remedy = "");

}  // namespace gesweep::archive

// The one place where zwidth decides what it may read and where it may write.
//
// Outputs are written to a temporary name beside the destination and renamed
// into place, so that a failure never leaves a half-written file (STYLE.md).
// An output must be a regular file (or a new name): a device, FIFO, socket or
// folder, or a symlink to one, is refused, and so is an output that is the same
// file (st_dev, st_ino) as an input of the command. A symlink to a regular file
// is followed: the file it names is replaced, the link stays. "-" writes to
// standard output. Temporary files and folders are registered, so that SIGINT,
// SIGTERM, SIGHUP, SIGPIPE and SIGXFSZ remove them before the process dies of
// the signal, once the program installed the handlers
// (InstallCleanupSignalHandlers: the zwidth command does; a library never
// replaces its host's handlers, e.g. Python's SIGINT -> KeyboardInterrupt,
// where the temporary files are removed as the exception unwinds instead).
//
// Inputs must be regular files (checked with stat before opening, so a FIFO
// cannot block and /dev/zero cannot be read forever); each one read is noted so
// that no output of the same command can replace it.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace zwidth::io {

// Throws InputError unless `path` names an existing regular file (symlinks
// followed); `what` says what it is ("log", "model file"). Notes the file as an
// input of this command (see CheckOutputPath).
void CheckInputFile(const std::string& path, const std::string& what);

// Throws InputError unless `path` may be written: "-", or a name in an existing
// folder that does not exist yet or is a regular file (symlinks followed), and
// that is not one of `inputs` nor an input noted so far. Used before long work,
// so that a bad -o fails at once rather than after the computation.
void CheckOutputPath(const std::string& path, const std::vector<std::string>& inputs = {});
// The same check (the historical name).
inline void CheckOutputFolder(const std::string& path, const std::vector<std::string>& inputs = {}) {
  CheckOutputPath(path, inputs);
}

// The rule of a single-file output's name (every `-o FILE` of the CLI, and
// Python's writers): an existing regular file is replaced, as cp replaces it
// (its mode kept); a folder or device is refused by CheckOutputPath; and a name
// whose extension is that of another format zwidth knows (.json, .csv, .h5,
// .mat, .m, .py, .html, ...: kKnownOutputExtensions) than the ones the output is
// written in (`extensions`, e.g. {".csv", ".txt", ".dat"}) is refused, so that
// `boundary -o model.json` cannot write a CSV over a model. No extension, or
// one zwidth does not know, is written in the output's format. `what` names the
// output ("a boundary CSV"). Throws InputError naming the path, the extension
// and the names accepted; "-" (standard output) passes.
void CheckOutputKind(const std::string& path, const std::string& what, const std::vector<std::string>& extensions);
// The extensions of a text table (CSV) output and of a log or response written as CSV or, by its extension, HDF5.
inline const std::vector<std::string> kCsvExtensions = {".csv", ".txt", ".dat"};
inline const std::vector<std::string> kCsvOrHdf5Extensions = {".csv", ".txt", ".dat", ".h5", ".hdf5", ".he5"};
// The extensions CheckOutputKind knows as some format's (lower case).
inline constexpr const char* kKnownOutputExtensions[] = {
    ".json", ".csv", ".tsv", ".txt", ".dat", ".h5", ".hdf5", ".he5", ".mat", ".m", ".py", ".html", ".htm",
    ".gp", ".svg", ".png", ".pdf", ".xml", ".yaml", ".yml", ".md"};

// Checks `path` (CheckOutputPath), calls write(tmp_path) and renames tmp_path
// onto the destination. tmp_path exists (empty) when write() is called. On any
// exception the temporary file is removed and the exception propagates; an
// error of the final fsync or rename is an InputError. For "-", the content is
// written to a temporary file and then copied to standard output.
void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write);

// Forgets the inputs noted so far (a long-lived process: each Python call is its own command).
void ForgetNotedInputs();
// The inputs noted so far, in the order first read, each once (the
// provenance's inputs, io/provenance.h).
std::vector<std::string> NotedInputs();

// Convenience: the whole content as text.
void WriteTextAtomically(const std::string& path, const std::string& content);

// Registry of live temporary paths, removed by the signal handler (see above)
// with unlink/rmdir only, which are async-signal-safe; a folder is emptied
// first (two levels deep). At most kMaxTempPaths at a time (then the path is
// simply not protected).
inline constexpr int kMaxTempPaths = 64;
// Installs that handler for SIGINT, SIGTERM, SIGHUP, SIGPIPE and SIGXFSZ (a
// signal the caller set to SIG_IGN, e.g. under nohup, stays ignored); then it
// re-raises the signal with its default action. For a program's main only.
void InstallCleanupSignalHandlers();
void RegisterTempPath(const std::string& path);
void UnregisterTempPath(const std::string& path);

// The output folder of `zwidth run`. The outputs are built in a temporary
// sibling folder (".NAME.tmp-XXXXXX" beside it) and moved into place by
// Commit(): renamed as a whole when the destination is new or empty (so two
// runs into one folder cannot mix: the second fails with an InputError), or,
// with force, file by file over the destination's files of the same names
// (other files are kept). Destroyed before Commit(), it removes the
// temporary folder: a failure leaves nothing, not even an empty folder.
class OutputFolder {
 public:
  // Throws InputError when `path` exists and is not a folder, is a non-empty
  // folder and !force, or when its parent folder does not exist.
  OutputFolder(const std::string& path, bool force);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::string& temp_path() const { return temp_; }
  const std::string& path() const { return path_; }
  void Commit();

 private:
  void DropLock();
  std::string path_, temp_;
  bool force_ = false, committed_ = false;
  int lock_fd_ = -1;
};

}  // namespace zwidth::io

// What a command must never write: its inputs. Whatever reads an input registers it here (a
// dataset registers every file it references and the folders that hold its images, commands
// register the files named on their command line), and every writer asks CheckOutput first:
// core/files/atomic_file.cpp does it for every file hdr4d writes, so no command can overwrite ground
// truth, write renders among a dataset's images or replace its own input, whatever the flags.
//
// A path matches a protected one by its resolved path (symlinks followed, also for files that do
// not exist yet) or by file identity (device and inode, so a hard link is caught too).
//
// The inputs are those of one command: registrations are kept while an InputProtectionScope is
// alive (the CLI opens one around every command, cli/app.cpp) and dropped when it ends, so a
// process that runs several commands in turn (tests, a benchmark harness) opens one per
// command. Without a scope nothing is registered and nothing is refused. Thread-safe.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace hdr4d {

// `role` finishes the sentence "refusing to write <path>: it is ...", e.g.
// "an image of dataset S (ground truth is never overwritten)".
void ProtectInputFile(const std::filesystem::path& file, const std::string& role);
// Nothing may be written directly inside `folder` (its sub-folders are not covered); `role`
// finishes "refusing to write into <folder>: it holds ...", e.g. "the images of dataset S".
void ProtectInputFolder(const std::filesystem::path& folder, const std::string& role);

// A path named on the command line as an input: a folder is protected as a folder, anything
// else as a file.
void ProtectInput(const std::filesystem::path& path, const std::string& role);

// Throws hdr4d::Error "<path>: refusing to write ..." when `path` is a protected file or lies
// directly inside a protected folder. `path` may be a symlink (its target is what is checked).
void CheckOutput(const std::filesystem::path& path);
// CheckOutput for one file a command was told to write (`eval --out F`, `synth-ldr -o F`): also
// refused when its folder holds a dataset's images found by looking (DatasetOfImageFolder), as
// CheckOutputFolder does for folders; the writers of many files keep CheckOutput alone, which
// costs no JSON reading per file.
void CheckOutputFile(const std::filesystem::path& path);
// The same for a folder a command is about to fill (call it before the work starts): refused when
// the folder is a protected folder or a protected file, or (inside a command) a dataset's image
// folder found by looking (DatasetOfImageFolder), also where the command read no dataset.
void CheckOutputFolder(const std::filesystem::path& folder);

// Paths the user named on the command line (cli/app.cpp registers every argument). A symlink or
// special file (FIFO, device) is written through only when its path was named so: one that is
// merely found inside an output folder (a planted `checkpoint.bin -> victim`) is replaced by
// the new file, never followed (core/files/atomic_file.cpp). Without a scope (library use)
// every path counts as named.
void NameOnCommandLine(const std::string& argument);
bool NamedOnCommandLine(const std::filesystem::path& path);

// True when `a` and `b` name the same file (same resolved path, or same device and inode).
bool SameFile(const std::filesystem::path& a, const std::filesystem::path& b);

// While alive, lets this process write exactly these files although they are protected dataset
// files or lie in protected folders: `synth-ldr --data` writes a dataset's LDR images, which is
// its job. The command checks first that none of them is one of its own inputs.
class OutputPermit {
 public:
  explicit OutputPermit(const std::vector<std::filesystem::path>& files);
  ~OutputPermit();
  OutputPermit(const OutputPermit&) = delete;
  OutputPermit& operator=(const OutputPermit&) = delete;

 private:
  std::vector<std::string> keys_;
};

// The files a training run writes into its folder (`train --overwrite` deletes exactly these;
// best_val.bin is --keep-best-val's best model). Inside a command, a folder holding `.hdr4d-lock`,
// or `config.json` and `checkpoint.bin`, is a run found by looking, and CheckOutput refuses these
// files and the lock there (`eval --out RUN/checkpoint.bin` would replace the trained model)
// unless this process trains that run and says so with a RunFolderWriter.
inline constexpr const char* kRunFolderFiles[] = {"checkpoint.bin", "config.json", "results.json",
                                                  "data_checksums.json", "best_val.bin"};

// While alive, this process may write the run files (kRunFolderFiles and the lock) of `run`: the
// trainer's.
class RunFolderWriter {
 public:
  explicit RunFolderWriter(const std::filesystem::path& run);
  ~RunFolderWriter();
  RunFolderWriter(const RunFolderWriter&) = delete;
  RunFolderWriter& operator=(const RunFolderWriter&) = delete;

 private:
  std::string key_;
};

// The lifetime of one command's registrations (nested scopes share the outermost one's).
class InputProtectionScope {
 public:
  InputProtectionScope();
  ~InputProtectionScope();
  InputProtectionScope(const InputProtectionScope&) = delete;
  InputProtectionScope& operator=(const InputProtectionScope&) = delete;
};

}  // namespace hdr4d

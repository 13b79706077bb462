// Work on an untrusted file in a child process. libhdf5 (1.10) can read out of
// bounds, even crash, on a corrupt file (our fuzzing found an H5Aexists crash);
// in a forked child such a crash becomes an InputError, not the end of zwidth.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

namespace zwidth::io {

// Sends one frame from the child to the parent (the child exits if the parent
// is gone).
using FrameSender = std::function<void(const void* data, size_t size)>;

// Runs produce(send) in a forked child; the parent receives each frame, in
// order, through consume(), while the child still runs (so a long file streams
// through in bounded memory). An exception thrown by produce() comes back as an
// InputError with its message; a crash of the child as an InputError naming
// `path`; an exception thrown by consume() ends the child and propagates.
// Where pipe() or fork() fail, produce() runs in this process.
void RunIsolated(const std::string& path, const std::function<void(const FrameSender&)>& produce,
                 const std::function<void(std::string_view frame)>& consume);

}  // namespace zwidth::io

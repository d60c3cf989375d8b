// What the batch tests put into the environment of the kanesim processes they start, so that
// a worker process ends the way it would in a release build also under the sanitizers
// (KANESIM_SANITIZE): AddressSanitizer would turn an injected SIGSEGV into its report and
// exit status 1 (handle_segv=0 leaves the signal to kill the worker), and end the process
// when an allocation exceeds --worker-memory's RLIMIT_AS (allocator_may_return_null=1:
// std::bad_alloc, as in a release build). Ignored by a build without the sanitizers.
#pragma once

#include <string>

namespace kanesim::batchtest {

// For a command line run by /bin/sh: keeps the caller's ASAN_OPTIONS (CI's detect_leaks=1).
inline const std::string kChildAsanOptions =
    "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}handle_segv=0:allocator_may_return_null=1\" ";

}  // namespace kanesim::batchtest

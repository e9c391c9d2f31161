// Running independent tasks (one shear pressure, one slope trial) as forked
// child processes, and the command line's exit codes.
#pragma once

#include <cstddef>
#include <functional>
#include <string_view>
#include <vector>

namespace centridem {

// Prints the exception being handled ("centridem: error: ...") and returns
// its exit code: 2 InputError, 3 InstabilityError, 128 + signal Interrupted,
// 1 anything else. Call inside a catch block.
int report_current_exception(std::string_view tag);

// Runs task(k) for k = 0 .. n-1. With jobs <= 1 in this process, in order
// (exceptions propagate). Otherwise each task in a forked child, at most
// `jobs` at once; a child's exception is reported with `tag(k)` and becomes
// its exit code. SIGINT / SIGTERM received by this process are forwarded to
// the running children, and no new task starts after one. Returns the exit
// code of each task (-1: not started).
std::vector<int> run_jobs(std::size_t n, int jobs, const std::function<void(std::size_t)>& task,
                          const std::function<std::string(std::size_t)>& tag);

} // namespace centridem

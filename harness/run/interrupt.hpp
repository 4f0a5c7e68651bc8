#pragma once
/// Ctrl-C and SIGTERM during a suite: the running child's process group is killed at once
/// (child_process.hpp), and the runner, seeing interrupted(), records no more jobs and stops;
/// `--resume` finishes the suite later.
namespace bvhbench {

/// Installs the SIGINT and SIGTERM handler. Idempotent.
void install_interrupt_handler();
/// Whether SIGINT or SIGTERM arrived since install_interrupt_handler().
bool interrupted();

}  // namespace bvhbench

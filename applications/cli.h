#ifndef SPINESIM_APPLICATIONS_CLI_H
#define SPINESIM_APPLICATIONS_CLI_H

// Command-line front end: parses argv with CLI11 and dispatches to the driver's commands.

namespace spinesim {

// Returns the process exit code (0 ok, 1 run failed, 2 bad input).
int run_cli(int argc, char** argv);

} // namespace spinesim

#endif

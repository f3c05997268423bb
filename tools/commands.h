// Subcommands of the `springmass` command-line tool, one per file (cmd_<name>.c). Each takes
// the arguments after its name (argv[0] is the subcommand name) and returns the exit status:
// 0 success, 1 a failure of the work itself (bad model, solver failure), 2 a usage error.
#pragma once

int sm_cmd_check(int argc, char** argv);
int sm_cmd_run(int argc, char** argv);
int sm_cmd_statics(int argc, char** argv);
int sm_cmd_modes(int argc, char** argv);
int sm_cmd_fmu(int argc, char** argv);

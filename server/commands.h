/* commands.h -- the iird subcommands; each returns the process exit code. */
#ifndef IIRD_COMMANDS_H
#define IIRD_COMMANDS_H

int iird_cmd_serve(int argc, char **argv);
int iird_cmd_params(int argc, char **argv);
int iird_cmd_render(int argc, char **argv);
int iird_cmd_raybench(int argc, char **argv);
int iird_cmd_bench(int argc, char **argv);

#endif

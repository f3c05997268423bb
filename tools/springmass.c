// springmass: the command-line tool. Dispatches to one subcommand per file.
#include "commands.h"

#include <stdio.h>
#include <string.h>

typedef struct command {
	const char* name;
	int (*run)(int argc, char** argv);
	const char* summary;
} command;

static const command commands[] = {
	{"check", sm_cmd_check, "validate a model file and print a summary"},
	{"run", sm_cmd_run, "simulate a model (CSV and VTK output)"},
	{"statics", sm_cmd_statics, "find the static equilibrium"},
	{"modes", sm_cmd_modes, "natural frequencies and mode shapes"},
	{"fmu", sm_cmd_fmu, "package a model file as an FMI 2.0 Co-Simulation FMU"},
};

static void usage(FILE* out)
{
	fprintf(out, "usage: springmass <command> [options]\n\ncommands:\n");
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) {
		fprintf(out, "  %-9s %s\n", commands[i].name, commands[i].summary);
	}
	fprintf(out, "\n`springmass <command> --help` explains a command.\n");
}

int main(int argc, char** argv)
{
	if (argc < 2) {
		usage(stderr);
		return 2;
	}
	if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
		usage(stdout);
		return 0;
	}
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) {
		if (strcmp(argv[1], commands[i].name) == 0) {
			return commands[i].run(argc - 1, argv + 1);
		}
	}
	fprintf(stderr, "springmass: unknown command '%s'\n\n", argv[1]);
	usage(stderr);
	return 2;
}

// springmass statics: placeholder until the subcommand lands.
#include "commands.h"

#include <stdio.h>

int sm_cmd_statics(int argc, char** argv)
{
	(void)argc;
	fprintf(stderr, "springmass %s: not available in this build\n", argv[0]);
	return 2;
}

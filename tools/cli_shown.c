// Paths and other text of the command line in the tool's messages (see cli_shown.h).
#include "cli_shown.h"

#include "springmass/model_file.h"

#include <stdlib.h>
#include <string.h>

const char* cli_shown_text(cli_shown* shown, const char* text)
{
	char* out = shown->count < CLI_SHOWN_PATHS ? malloc(SM_TERMINAL_TEXT_CAPACITY(strlen(text))) : NULL;
	if (out == NULL)
		return "(out of memory)";
	sm_text_for_terminal(out, text);
	shown->text[shown->count++] = out;
	return out;
}

const char* cli_shown_path(cli_shown* shown, const char* path)
{
	return cli_shown_text(shown, path);
}

void cli_shown_free(cli_shown* shown)
{
	for (int k = 0; k < shown->count; k++)
		free(shown->text[k]);
	shown->count = 0;
}

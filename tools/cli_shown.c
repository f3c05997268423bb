// Paths in the tool's messages (see cli_shown.h).
#include "cli_shown.h"

#include "springmass/model_file.h"

#include <stdlib.h>
#include <string.h>

const char* cli_shown_path(cli_shown* shown, const char* path)
{
	char* text = shown->count < CLI_SHOWN_PATHS ? malloc(SM_TERMINAL_TEXT_CAPACITY(strlen(path))) : NULL;
	if (text == NULL)
		return "(out of memory)";
	sm_text_for_terminal(text, path);
	shown->text[shown->count++] = text;
	return text;
}

void cli_shown_free(cli_shown* shown)
{
	for (int k = 0; k < shown->count; k++)
		free(shown->text[k]);
	shown->count = 0;
}

// Paths and other text of the command line in the tool's messages.
#pragma once

/// Most texts one message shows (cli_shown_path, cli_shown_text).
#define CLI_SHOWN_PATHS 4

/// The texts of one message as cli_shown_path and cli_shown_text show them, kept until
/// cli_shown_free. Starts as {0}.
typedef struct cli_shown {
	char* text[CLI_SHOWN_PATHS];
	int count;
} cli_shown;

/// A file's or folder's path for a message, as the library shows a model file's or an OBJ file's:
/// what a terminal would act on or not show (control characters such as ESC, line breaks, bytes
/// that are not UTF-8) escaped as sm_text_for_terminal escapes them ("\u001b[31m", "\u000a",
/// "\xff"), everything else as it is. It is shown whole, however long: a message of the tool has
/// no size limit, which is why the library shows a path longer than 140 bytes by its end. The text
/// stays in `shown` until cli_shown_free; "(out of memory)" when there is no room for it.
const char* cli_shown_path(cli_shown* shown, const char* path);

/// Any other text of the command line or the environment for a message (an unknown option or
/// command, an option's refused value, a --set NAME=VALUE, a parameter's name), shown as
/// cli_shown_path shows a path: escaped, whole, kept in `shown` until cli_shown_free.
const char* cli_shown_text(cli_shown* shown, const char* text);

/// Frees the texts cli_shown_path and cli_shown_text kept in `shown`, which is then empty.
void cli_shown_free(cli_shown* shown);

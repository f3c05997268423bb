// Outputs written all or none (cli_outputs.h).
#define _XOPEN_SOURCE 700  // fchmod, fdopen
#include "cli_outputs.h"

#include "cli_common.h"
#include "cli_signals.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

// The temporary name of output k: in the folder of path, ".springmass-<pid>-<k>.partial", short,
// so that an output whose name is as long as the file system allows has one beside it too.
static char* temporary_name(const char* path, int k)
{
	const char* slash = strrchr(path, '/');
	const int folder = slash != NULL ? (int)(slash - path) + 1 : 0;
	const size_t capacity = (size_t)folder + 64;
	char* name = malloc(capacity);
	if (name != NULL)
		snprintf(name, capacity, "%.*s.springmass-%ld-%d.partial", folder, path, (long)getpid(), k);
	return name;
}

// Opens the temporary beside a regular file or a new one: 0666 less the umask, as fopen would
// create it, or the permissions of the file it replaces. A file that may not be written is
// refused as fopen would refuse it (the rename would replace it all the same).
static FILE* open_temporary(const char* temporary, const char* path)
{
	struct stat st;
	const bool exists = stat(path, &st) == 0;
	if (exists && access(path, W_OK) != 0)
		return NULL;
	const int fd = open(temporary, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
	if (fd < 0)
		return NULL;
	FILE* f = exists && fchmod(fd, st.st_mode & 07777) != 0 ? NULL : fdopen(fd, "w");
	if (f == NULL) {
		const int error = errno;
		close(fd);
		unlink(temporary);
		errno = error;
	}
	return f;
}

FILE* cli_outputs_open(cli_outputs* outputs, const char* path)
{
	// A write to an output or to standard output that is a pipe without a reader fails instead of
	// ending the command before it has removed its temporaries (cli_outputs_discard).
	if (outputs->count == 0 && !outputs->pipe_held)
		outputs->pipe_held = cli_hold_pipe_signal();
	if (outputs->count == outputs->capacity) {
		const int capacity = 2 * outputs->capacity + 4;
		cli_output* items = realloc(outputs->items, (size_t)capacity * sizeof *items);
		if (items == NULL) {
			fprintf(stderr, "springmass %s: out of memory\n", outputs->command);
			return NULL;
		}
		outputs->items = items;
		outputs->capacity = capacity;
	}
	cli_output item = {NULL, strdup(path)};
	struct stat st;
	bool direct = lstat(path, &st) == 0 && !S_ISREG(st.st_mode);
	if (item.path != NULL && !direct)
		item.temporary = temporary_name(path, outputs->count);
	if (item.path == NULL || (!direct && item.temporary == NULL)) {
		free(item.path);
		free(item.temporary);
		fprintf(stderr, "springmass %s: out of memory\n", outputs->command);
		return NULL;
	}
	errno = 0;
	FILE* f = direct ? NULL : open_temporary(item.temporary, path);
	// A file in a folder that takes no new files (nor the temporary) is rewritten where it is.
	const int error = errno;
	if (!direct && f == NULL && (error == EACCES || error == EPERM || error == EROFS) &&
	    lstat(path, &st) == 0 && access(path, W_OK) == 0) {
		free(item.temporary);
		item.temporary = NULL;
		direct = true;
	}
	errno = error;
	if (direct)
		f = fopen(path, "w");
	if (f == NULL) {
		cli_cannot_write(outputs->command, path);
		free(item.path);
		free(item.temporary);
		return NULL;
	}
	outputs->items[outputs->count++] = item;
	return f;
}

int cli_outputs_commit(cli_outputs* outputs)
{
	for (int k = 0; k < outputs->count; k++) {
		cli_output* item = &outputs->items[k];
		if (item->temporary == NULL)
			continue;
		errno = 0;
		if (rename(item->temporary, item->path) != 0) {
			cli_cannot_write(outputs->command, item->path);
			return -1;
		}
		free(item->temporary);
		item->temporary = NULL;
	}
	return 0;
}

void cli_outputs_discard(cli_outputs* outputs)
{
	for (int k = 0; k < outputs->count; k++) {
		if (outputs->items[k].temporary != NULL)
			unlink(outputs->items[k].temporary);
		free(outputs->items[k].temporary);
		free(outputs->items[k].path);
	}
	free(outputs->items);
	outputs->items = NULL;
	outputs->count = outputs->capacity = 0;
	cli_release_pipe_signal(outputs->pipe_held);
	outputs->pipe_held = false;
}

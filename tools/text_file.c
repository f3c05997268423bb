// Whole text files read at once (see text_file.h).
#define _POSIX_C_SOURCE 200809L

#include "text_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

char* text_file_read(const char* path, size_t* length, const char** problem)
{
	const char* unused;
	if (problem == NULL)
		problem = &unused;
	// O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever; it is refused below.
	const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0) {
		*problem = strerror(errno);
		return NULL;
	}
	struct stat st;
	char* data = NULL;
	if (fstat(fd, &st) != 0) {
		*problem = strerror(errno);
	} else if (!S_ISREG(st.st_mode)) {
		*problem = S_ISDIR(st.st_mode) ? "it is a directory" : "not a regular file";
		errno = S_ISDIR(st.st_mode) ? EISDIR : EINVAL;
	} else if (st.st_size > TEXT_FILE_MAX_BYTES) {
		*problem = "larger than 1 GiB";
		errno = EFBIG;
	} else if ((data = malloc((size_t)st.st_size + 1)) == NULL) {
		*problem = strerror(errno = ENOMEM);
	} else {
		// Reads st_size bytes, then one more to see that the file did not grow meanwhile.
		const size_t size = (size_t)st.st_size;
		size_t got = 0;
		char extra;
		ssize_t r = 0;
		while (got < size && ((r = read(fd, data + got, size - got)) > 0 || (r < 0 && errno == EINTR)))
			got += r > 0 ? (size_t)r : 0;
		if (r >= 0 && got == size)
			while ((r = read(fd, &extra, 1)) < 0 && errno == EINTR)
				;
		if (r != 0 || got != size) {
			*problem = r < 0 ? strerror(errno) : "the file changed while it was read";
			if (r >= 0)
				errno = EAGAIN;
			free(data);
			data = NULL;
		} else {
			data[size] = '\0';
			*length = size;
		}
	}
	const int error = errno;
	close(fd);
	errno = error;
	return data;
}

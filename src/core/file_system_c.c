/* Directory and file operations for Fortran through system calls (standard Fortran has no
 * mkdir, rmdir or unlink). Paths are taken literally: no shell ever sees them. */
#define _GNU_SOURCE   /* O_PATH */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* mkdir -p: creates `path` (NUL-terminated) and every missing parent with mode 0777 (less the
 * umask). Returns 0 when `path` is a directory afterwards, else the errno of the failing step. */
int agglo_make_directories(const char *path)
{
    size_t length = strlen(path);
    char *partial;
    struct stat info;
    size_t i;
    int status = 0;
    if (length == 0) return ENOENT;
    partial = malloc(length + 1);
    if (partial == NULL) return ENOMEM;
    memcpy(partial, path, length + 1);
    /* Each prefix that ends before a '/' (and the whole path) in turn; repeated slashes give
     * prefixes that exist already. */
    for (i = 1; i <= length && status == 0; i++) {
        if (i < length && partial[i] != '/') continue;
        partial[i] = '\0';
        if (mkdir(partial, 0777) != 0 && errno != EEXIST) status = errno;
        else if (stat(partial, &info) != 0) status = errno;
        else if (!S_ISDIR(info.st_mode)) status = ENOTDIR;
        if (i < length) partial[i] = '/';
    }
    free(partial);
    return status;
}

/* Removes the file or the empty directory `path` (C's remove()). Returns 0 or errno. */
int agglo_remove_path(const char *path)
{
    return remove(path) == 0 ? 0 : errno;
}

/* Writes the text of errno value `code` into `buffer` (capacity bytes, NUL-terminated). */
void agglo_error_text(int code, char *buffer, int capacity)
{
    if (capacity <= 0) return;
    strncpy(buffer, strerror(code), (size_t)capacity - 1);
    buffer[capacity - 1] = '\0';
}

/* Opens the directory `path` as a handle for names below it (O_PATH where the system has it:
 * no read permission needed). Returns the descriptor, or -1 with nothing opened. */
int agglo_open_directory(const char *path)
{
#ifdef O_PATH
    return open(path, O_PATH | O_DIRECTORY | O_CLOEXEC);
#else
    return open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
#endif
}

/* Closes a descriptor of agglo_open_directory. Returns 0 or errno. */
int agglo_close_directory(int descriptor)
{
    return close(descriptor) == 0 ? 0 : errno;
}

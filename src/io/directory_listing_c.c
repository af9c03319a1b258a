/* Directory listing for Fortran (standard Fortran has none): the names in one directory. */
#include <dirent.h>
#include <string.h>

/* Writes the entry names of directory `path` (NUL-terminated) into `buffer`, each followed by
 * '\n', skipping "." and "..". Returns the number of bytes the whole list needs: when that
 * exceeds `capacity` the list was cut and the caller retries with a larger buffer.
 * Returns -1 when the directory cannot be opened. */
int agglo_list_directory(const char *path, char *buffer, int capacity)
{
    DIR *directory = opendir(path);
    struct dirent *entry;
    int needed = 0;
    if (directory == NULL) return -1;
    while ((entry = readdir(directory)) != NULL) {
        size_t length = strlen(entry->d_name);
        if (strcmp(entry->d_name, ".") == 0 || strcmp(entry->d_name, "..") == 0) continue;
        if (needed + (int)length + 1 <= capacity) {
            memcpy(buffer + needed, entry->d_name, length);
            buffer[needed + (int)length] = '\n';
        }
        needed += (int)length + 1;
    }
    closedir(directory);
    return needed;
}

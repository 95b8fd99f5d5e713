/* Runs the fuzz harness (fuzz_api.c) on files, as libFuzzer does with files
 * on its command line, for builds without libFuzzer: each argument is a file
 * or a directory of files (run in name order). A failed check aborts. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "fuzz replay: cannot open %s\n", path);
        return 1;
    }
    uint8_t *data = NULL;
    size_t size = 0, cap = 0, got;
    do {
        if (size == cap) {
            cap = cap ? 2 * cap : 4096;
            uint8_t *more = realloc(data, cap);
            if (!more) {
                fprintf(stderr, "fuzz replay: out of memory\n");
                exit(1);
            }
            data = more;
        }
        got = fread(data + size, 1, cap - size, f);
        size += got;
    } while (got > 0);
    fclose(f);
    fprintf(stderr, "fuzz replay: %s (%zu bytes)\n", path, size);
    LLVMFuzzerTestOneInput(data, size);
    free(data);
    return 0;
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

int main(int argc, char **argv) {
    int files = 0, errors = 0;
    for (int k = 1; k < argc; ++k) {
        struct stat st;
        if (stat(argv[k], &st) != 0) {
            fprintf(stderr, "fuzz replay: no such file or directory: %s\n", argv[k]);
            ++errors;
            continue;
        }
        if (!S_ISDIR(st.st_mode)) {
            errors += run_file(argv[k]);
            ++files;
            continue;
        }
        DIR *dir = opendir(argv[k]);
        if (!dir) {
            fprintf(stderr, "fuzz replay: cannot read %s\n", argv[k]);
            ++errors;
            continue;
        }
        char **names = NULL;
        size_t n = 0;
        for (struct dirent *e; (e = readdir(dir)) != NULL;) {
            if (e->d_name[0] == '.') continue;
            char **more = realloc(names, sizeof(char *) * (n + 1));
            const size_t len = strlen(argv[k]) + strlen(e->d_name) + 2;
            if (!more || !(more[n] = malloc(len))) {
                fprintf(stderr, "fuzz replay: out of memory\n");
                return 1;
            }
            names = more;
            snprintf(names[n++], len, "%s/%s", argv[k], e->d_name);
        }
        closedir(dir);
        qsort(names, n, sizeof(char *), by_name);
        for (size_t i = 0; i < n; ++i) {
            errors += run_file(names[i]);
            ++files;
            free(names[i]);
        }
        free(names);
    }
    printf("fuzz replay: %d inputs run, %d unreadable\n", files, errors);
    return errors || files == 0 ? 1 : 0;
}

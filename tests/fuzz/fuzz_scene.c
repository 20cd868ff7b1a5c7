/* libFuzzer target: the scene-file (INI) parser, bkf_scene_parse_string
 * (include/bkfront/scene.h).  The Makefile builds it only once src/scene.c
 * exists.  The whole input is the file's text; a parsed scene must be freed
 * without error, and a rejection must follow the error contract. */
#include "fuzz_common.h"

#include "bkfront/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = fuzz_string(data, size);
    bkf_scene *scene = NULL;
    bkf_error e = {{0}};
    int s = bkf_scene_parse_string(text, "fuzz.scene", &scene, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) FUZZ_CHECK(scene != NULL);
    bkf_scene_free(scene);
    free(text);
    return 0;
}

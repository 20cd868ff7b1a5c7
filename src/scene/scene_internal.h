/* Internal to the scene (src/scene/scene.c, scene_keys.c, scene_plan.c,
 * scene_run.c, scene_jobs.c): the types and the pieces the files share.
 * Dependencies point one way: scene.c (parsing and checking a scene) ->
 * scene_plan.c (the plan) -> scene_keys.c (the kinds, their keys, where a
 * value comes from); scene_jobs.c (the workers) -> scene_run.c (one step)
 * -> scene_plan.c, scene_keys.c.  Not installed, not part of the API. */
#ifndef BKFRONT_SCENE_INTERNAL_H
#define BKFRONT_SCENE_INTERNAL_H

#include <stddef.h>

#include "bkfront/catalog.h"
#include "bkfront/options.h"
#include "bkfront/scene.h"

/* At most this many values in a list key: a list such as nu = A:B:N is one
 * computation per value, planned and run one by one, so the cap is that of
 * a range of computations, not the 1e6 of values inside one product. */
#define SCENE_MAX_POINTS 100000u

/* A kind of section: its name and, but for figure, the catalogue entry
 * that declares it. */
typedef struct {
    const char *name;
    const bkf_catalog_entry *entry;  /* NULL: figure */
    const bkf_catalog_kind *decl;
} scene_kind_info;

/* NULL: no such kind. */
const scene_kind_info *scene_kind_at(int kind);
/* The kind's name, "?" for none. */
const char *scene_kind_name(bkf_scene_kind kind);

/* Open addressing over item indices, so that finding a product by name
 * while parsing and a computation already planned cost O(1) each: a scene
 * of 50,000 products used to take 46 s to plan (every step compared with
 * every earlier one).  Slots hold index + 1 (0: empty) with its hash. */
typedef struct {
    size_t *item, *hash;
    size_t cap, count;
} scene_lookup;

#define SCENE_HASH_SEED ((size_t)14695981039346656037u)
size_t scene_hash_text(size_t h, const char *s);
void scene_lookup_free(scene_lookup *l);
/* The first index i with this hash and same(i, data), or SIZE_MAX. */
size_t scene_lookup_find(const scene_lookup *l, size_t h, int (*same)(size_t, const void *),
                         const void *data);
/* 0 when out of memory. */
int scene_lookup_add(scene_lookup *l, size_t h, size_t index);
/* `array` with room for element `count` (NULL: out of memory). */
void *scene_grow_for_push(void *array, size_t count, size_t size);

/* What scene_same_name compares: a product's name, figures apart. */
typedef struct {
    const bkf_scene *s;
    const char *name;
    int figure;
} scene_name_query;
int scene_same_name(size_t i, const void *data);

/* The catalogue's options as a scene sees them. */
const bkf_option *scene_fanout_option(const bkf_catalog_entry *entry);
const char *scene_option_name(const char *key, char *buf, size_t size);
const bkf_option *scene_catalog_option(const bkf_catalog_entry *entry, const char *name);
int scene_apply_args(const bkf_catalog_entry *entry, const bkf_scene_arg *args, size_t n,
                     void *spec, int outputs, size_t *bad, bkf_error *err);

/* One item of a kind's keys (catalog.h's bkf_catalog_step): KEY and its
 * marks. */
typedef struct {
    char key[64];
    int inherit, required, names, always, has_value; /* ^ (+), +, @, :=, = */
    char value[BKF_SCENE_VALUE_LEN];       /* =TEXT, =$OTHER, :=TEXT */
    char omit[64];                         /* !TEXT */
    char if_key[64], if_value[64];         /* ?OTHER=TEXT */
} scene_key_item;
scene_key_item *scene_parse_items(const char *text, size_t *n);

/* Where a section's values come from. */
const char *scene_entry_value(const bkf_scene_entry *list, size_t n, const char *key);
const char *scene_own_value(const bkf_scene_product *p, const char *key);
const char *scene_key(const bkf_scene *s, const bkf_scene_product *p, const char *key,
                      int inherit);
int scene_takes_inherited(const bkf_scene_product *p, const char *key);
int scene_key_line(const bkf_scene *s, const bkf_scene_product *p, const char *key);
int scene_figure_data(const bkf_scene *s, const char *data, size_t **out, size_t *count,
                      char *bad, size_t badsize);

/* Texts. */
int scene_list_values(const char *text, char ***items, size_t *count);
void scene_list_values_free(char **items, size_t count);
/* text after buf's text, with sep between; 0 when it did not fit. */
int scene_append(char *buf, size_t size, const char *sep, const char *text);

#endif

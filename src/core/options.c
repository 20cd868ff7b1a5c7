#include "bkfront/options.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NUMBER_FORM "a finite decimal number such as 2, -0.5 or 1e-3"

const char *bkf_option_shown(const char *text, char *buf, size_t size)
{
    size_t n = 0, limit = size - 4;
    const unsigned char *s = (const unsigned char *)(text ? text : "");
    for (; *s && n < limit; s++) buf[n++] = (*s < 0x20 || *s == 0x7f) ? '?' : (char)*s;
    if (*s) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n] = '\0';
    return buf;
}

const char *bkf_format_number(double x, char *buf, size_t size)
{
    if (isnan(x)) {
        snprintf(buf, size, "nan");
        return buf;
    }
    if (isinf(x)) {
        snprintf(buf, size, x > 0 ? "inf" : "-inf");
        return buf;
    }
    /* %.17g always reads back; the first shorter one that does is the
     * shortest, since fewer digits can only round further away. */
    int digits = 1;
    for (; digits < 17; digits++) {
        snprintf(buf, size, "%.*g", digits, x);
        if (strtod(buf, NULL) == x) break;
    }
    /* 100 as "100", not "1e+02": an integer part of up to 15 digits is
     * written out (as %.15g would). */
    int exponent = x != 0 ? (int)floor(log10(fabs(x))) : 0;
    if (exponent >= digits && exponent < 15) digits = exponent + 1;
    snprintf(buf, size, "%.*g", digits, x);
    return buf;
}

/* ------------------------------------------------------------ scalars */

static int is_nonfinite_word(const char *s)
{
    if (*s == '+' || *s == '-') s++;
    static const char *const words[] = {"nan", "inf", "infinity"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++) {
        size_t n = strlen(words[i]);
        size_t j = 0;
        for (; j < n && s[j]; j++)
            if ((s[j] | 0x20) != words[i][j]) break;
        if (j == n && (s[j] == '\0' || s[j] == '(')) return 1;
    }
    return 0;
}

typedef enum { NUM_OK, NUM_MALFORMED, NUM_NONFINITE, NUM_OVERFLOW } number_verdict;

static number_verdict read_double(const char *text, double *value)
{
    if (is_nonfinite_word(text)) return NUM_NONFINITE;
    /* Only the characters of a decimal number: this is what shuts out
     * strtod's hex floats, nan(...), infinities and leading white space. */
    if (!*text || strspn(text, "0123456789+-.eE") != strlen(text)) return NUM_MALFORMED;
    char *end;
    errno = 0;
    double x = strtod(text, &end);
    if (end == text || *end != '\0') return NUM_MALFORMED;
    /* ERANGE on underflow still gives a usable (tiny or zero) value. */
    if (!isfinite(x)) return NUM_OVERFLOW;
    *value = x;
    return NUM_OK;
}

/* "--mu: 'abc' is not a number (...)", or with the list it came from:
 * "--mu: 'abc' in '1:abc:3' is not a number (...)". */
static int number_error(bkf_error *err, const char *prefix, const char *name, const char *part,
                        const char *context, number_verdict verdict)
{
    char a[72], b[72];
    const char *what = verdict == NUM_NONFINITE ? "is not a finite number"
                       : verdict == NUM_OVERFLOW ? "is too large for a double"
                                                 : "is not a number";
    if (context)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' in '%s' %s (expected %s)", prefix,
                             name, bkf_option_shown(part, a, sizeof a),
                             bkf_option_shown(context, b, sizeof b), what, NUMBER_FORM);
    return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' %s (expected %s)", prefix, name,
                         bkf_option_shown(part, a, sizeof a), what, NUMBER_FORM);
}

int bkf_option_parse_double(const char *text, const char *prefix, const char *name,
                            double *value, bkf_error *err)
{
    double x = 0;
    number_verdict v = read_double(text ? text : "", &x);
    if (v != NUM_OK) return number_error(err, prefix, name, text ? text : "", NULL, v);
    *value = x;
    return BKF_OK;
}

static int read_unsigned(const char *text, uint64_t max, uint64_t *value)
{
    if (!*text || strspn(text, "0123456789") != strlen(text)) return 0;
    uint64_t n = 0;
    for (const char *p = text; *p; p++) {
        uint64_t d = (uint64_t)(*p - '0');
        if (d > max || n > (max - d) / 10) return 0; /* n * 10 + d > max */
        n = n * 10 + d;
    }
    *value = n;
    return 1;
}

int bkf_option_parse_count(const char *text, size_t min, size_t max, const char *prefix,
                           const char *name, size_t *value, bkf_error *err)
{
    char a[72];
    uint64_t n;
    if (!read_unsigned(text ? text : "", max, &n) || n < min)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not an integer in [%zu, %zu]",
                             prefix, name, bkf_option_shown(text, a, sizeof a), min, max);
    *value = (size_t)n;
    return BKF_OK;
}

static void choice_list(const char *const *choices, char *list, size_t size)
{
    list[0] = '\0';
    for (int i = 0; choices[i]; i++) {
        size_t used = strlen(list);
        snprintf(list + used, size - used, "%s%s", i ? ", " : "", choices[i]);
    }
}

int bkf_option_parse_choice(const char *text, const char *const *choices, const char *prefix,
                            const char *name, int *index, bkf_error *err)
{
    char list[256], a[72];
    for (int i = 0; choices[i]; i++)
        if (text && strcmp(text, choices[i]) == 0) {
            *index = i;
            return BKF_OK;
        }
    choice_list(choices, list, sizeof list);
    return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not one of %s", prefix, name,
                         bkf_option_shown(text, a, sizeof a), list);
}

/* --------------------------------------------------------------- lists */

void bkf_list_free(bkf_list *list)
{
    if (!list) return;
    free(list->values);
    *list = (bkf_list){0};
}

static int list_alloc(bkf_list *list, size_t count, const char *prefix, const char *name,
                      bkf_error *err)
{
    list->values = malloc(count * sizeof *list->values);
    if (!list->values)
        return bkf_error_set(err, BKF_ENOMEM, "%s%s: out of memory", prefix, name);
    list->count = count;
    return BKF_OK;
}

static const char *list_form(int geometric, int integer)
{
    if (integer) return "an integer K, a list K1,K2,... or a range A:B:N";
    return geometric ? "a number > 0 or a geometric range A:B:N with A, B > 0"
                     : "a number or a range A:B:N";
}

/* "A:B:N" into list (count points). */
static int parse_range(const char *text, const char *c1, const char *c2, int geometric,
                       int integer, size_t max, const char *prefix, const char *name,
                       bkf_list *list, bkf_error *err)
{
    char a[72], b[72];
    double from = 0, to = 0;
    size_t la = (size_t)(c1 - text), lb = (size_t)(c2 - c1 - 1);
    char *pa = malloc(la + 1), *pb = malloc(lb + 1);
    if (!pa || !pb) {
        free(pa);
        free(pb);
        return bkf_error_set(err, BKF_ENOMEM, "%s%s: out of memory", prefix, name);
    }
    memcpy(pa, text, la);
    pa[la] = '\0';
    memcpy(pb, c1 + 1, lb);
    pb[lb] = '\0';
    number_verdict va = read_double(pa, &from), vb = read_double(pb, &to);
    int status = BKF_OK;
    if (va != NUM_OK)
        status = number_error(err, prefix, name, pa, text, va);
    else if (vb != NUM_OK)
        status = number_error(err, prefix, name, pb, text, vb);
    free(pa);
    free(pb);
    if (status) return status;
    uint64_t count;
    if (!read_unsigned(c2 + 1, max, &count) || count < 1)
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: N = '%s' in '%s' is not an integer in [1, %zu]", prefix, name,
                             bkf_option_shown(c2 + 1, a, sizeof a),
                             bkf_option_shown(text, b, sizeof b), max);
    if (count == 1 && from != to)
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: '%s' has N = 1 point, so A and B must be equal "
                             "(or give the single value A)",
                             prefix, name, bkf_option_shown(text, a, sizeof a));
    /* Integer ranges step in integers: 1:10:10 is 1, 2, ..., 10 exactly,
     * which the weighted sum below would miss by an ulp. */
    double step = 0;
    if (integer) {
        if (from != floor(from) || to != floor(to) || fabs(from) > 9e15 || fabs(to) > 9e15)
            return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not %s (A and B integers)",
                                 prefix, name, bkf_option_shown(text, a, sizeof a),
                                 list_form(geometric, integer));
        if (count > 1) {
            step = (to - from) / (double)(count - 1);
            if (step != floor(step))
                return bkf_error_set(err, BKF_EINPUT,
                                     "%s%s: '%s' does not step by an integer (B - A must be a "
                                     "multiple of N - 1)",
                                     prefix, name, bkf_option_shown(text, a, sizeof a));
        }
    }
    if (geometric && !(from > 0 && to > 0))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not %s (the points are geometric)",
                             prefix, name, bkf_option_shown(text, a, sizeof a),
                             list_form(geometric, 0));
    int s = list_alloc(list, (size_t)count, prefix, name, err);
    if (s) return s;
    double lga = geometric ? log(from) : 0, lgb = geometric ? log(to) : 0;
    for (size_t i = 0; i < count; i++) {
        double t = count > 1 ? (double)i / (double)(count - 1) : 0.0;
        /* Weighted sum rather than from + i h: no overflow for ends of
         * opposite sign near DBL_MAX, and t = 0 and 1 give the ends. */
        if (integer && !geometric)
            list->values[i] = from + step * (double)i;
        else
            list->values[i] = geometric ? exp(lga * (1 - t) + lgb * t) : from * (1 - t) + to * t;
        if (integer) list->values[i] = nearbyint(list->values[i]);
    }
    list->values[0] = from;
    list->values[count - 1] = to;
    list->is_range = 1;
    return BKF_OK;
}

/* "V1,V2,..." (at least one comma). */
static int parse_items(const char *text, int geometric, int integer, size_t max,
                       const char *prefix, const char *name, bkf_list *list, bkf_error *err)
{
    size_t n = 1;
    for (const char *p = text; *p; p++) n += *p == ',';
    if (n > max)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: more than %zu values", prefix, name, max);
    size_t len = strlen(text);
    char *copy = malloc(len + 1);
    if (!copy) return bkf_error_set(err, BKF_ENOMEM, "%s%s: out of memory", prefix, name);
    int s = list_alloc(list, n, prefix, name, err);
    if (s) {
        free(copy);
        return s;
    }
    memcpy(copy, text, len + 1);
    /* strtok would merge ",," into one separator and hide an empty item. */
    char *item = copy;
    for (size_t i = 0; i < n && !s; i++) {
        char *comma = strchr(item, ',');
        if (comma) *comma = '\0';
        if (!*item)
            s = bkf_error_set(err, BKF_EINPUT, "%s%s: empty item in the list (expected %s)",
                              prefix, name, list_form(geometric, integer));
        else if (integer) {
            size_t k = 0;
            s = bkf_option_parse_count(item, 0, (size_t)1 << 53, prefix, name, &k, err);
            list->values[i] = (double)k;
        } else {
            number_verdict v = read_double(item, &list->values[i]);
            if (v != NUM_OK) s = number_error(err, prefix, name, item, text, v);
        }
        if (!s && geometric && !(list->values[i] > 0)) {
            char a[72];
            s = bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' in '%s' is not > 0 (the list is "
                              "geometric)", prefix, name, item,
                              bkf_option_shown(text, a, sizeof a));
        }
        item = comma ? comma + 1 : item + strlen(item);
    }
    free(copy);
    if (s) return s;
    list->is_range = 1;
    return BKF_OK;
}

int bkf_list_parse(const char *text, int geometric, int integer, size_t max, const char *prefix,
                   const char *name, bkf_list *list, bkf_error *err)
{
    char a[72];
    *list = (bkf_list){0};
    if (!text) text = "";
    if (!prefix) prefix = "";
    if (max == 0 || max > BKF_LIST_MAX) max = BKF_LIST_MAX;
    const char *c1 = strchr(text, ':');
    const char *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    int s;
    if ((c1 && !c2) || (c2 && strchr(c2 + 1, ':')) || (c1 && strchr(text, ',')))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not %s", prefix, name,
                             bkf_option_shown(text, a, sizeof a), list_form(geometric, integer));
    if (c1)
        s = parse_range(text, c1, c2, geometric, integer, max, prefix, name, list, err);
    else if (strchr(text, ','))
        s = parse_items(text, geometric, integer, max, prefix, name, list, err);
    else {
        double x = 0;
        if (integer) {
            size_t k = 0;
            s = bkf_option_parse_count(text, 0, (size_t)1 << 53, prefix, name, &k, err);
            x = (double)k;
        } else {
            number_verdict v = read_double(text, &x);
            s = v == NUM_OK ? BKF_OK : number_error(err, prefix, name, text, NULL, v);
        }
        if (!s && geometric && !(x > 0))
            s = bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not %s (the points are geometric)",
                              prefix, name, bkf_option_shown(text, a, sizeof a),
                              list_form(geometric, 0));
        if (!s && !(s = list_alloc(list, 1, prefix, name, err))) list->values[0] = x;
    }
    if (s) {
        bkf_list_free(list);
        return s;
    }
    list->from = list->values[0];
    list->to = list->values[list->count - 1];
    return BKF_OK;
}

/* -------------------------------------------------------------- table */

const bkf_option *bkf_option_find(const bkf_option *table, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (name && strcmp(table[i].name, name) == 0) return &table[i];
    return NULL;
}

/* "[1e-06, 1e+06]", "(-1, 1)", ">= 0", "> 0", "<= 5": the bounds that apply. */
static const char *bounds_text(const bkf_option *opt, char *buf, size_t size)
{
    char a[32], b[32];
    int lo = (opt->flags & BKF_OPT_MIN) != 0, hi = (opt->flags & BKF_OPT_MAX) != 0;
    const char *lo_op = (opt->flags & BKF_OPT_MIN_OPEN) ? ">" : ">=";
    const char *hi_op = (opt->flags & BKF_OPT_MAX_OPEN) ? "<" : "<=";
    /* %g: bounds are round constants, and 1e+06 reads better than 1000000. */
    snprintf(a, sizeof a, "%g", opt->min);
    snprintf(b, sizeof b, "%g", opt->max);
    if (lo && hi)
        snprintf(buf, size, "in %c%s, %s%c", (opt->flags & BKF_OPT_MIN_OPEN) ? '(' : '[', a, b,
                 (opt->flags & BKF_OPT_MAX_OPEN) ? ')' : ']');
    else if (lo)
        snprintf(buf, size, "%s %s", lo_op, a);
    else if (hi)
        snprintf(buf, size, "%s %s", hi_op, b);
    else
        buf[0] = '\0';
    return buf;
}

static int in_bounds(const bkf_option *opt, double x)
{
    if (opt->flags & BKF_OPT_MIN) {
        if ((opt->flags & BKF_OPT_MIN_OPEN) ? !(x > opt->min) : !(x >= opt->min)) return 0;
    }
    if (opt->flags & BKF_OPT_MAX) {
        if ((opt->flags & BKF_OPT_MAX_OPEN) ? !(x < opt->max) : !(x <= opt->max)) return 0;
    }
    return 1;
}

/* The integer bounds of a count: [min, max], default [1, SIZE_MAX]. */
static void count_bounds(const bkf_option *opt, size_t *lo, size_t *hi)
{
    *lo = 1;
    *hi = SIZE_MAX;
    if (opt->flags & BKF_OPT_MIN) {
        double m = ceil(opt->min + ((opt->flags & BKF_OPT_MIN_OPEN) ? 0.5 : 0));
        *lo = m <= 0 ? 0 : (size_t)m;
    }
    if (opt->flags & BKF_OPT_MAX) {
        double m = floor(opt->max - ((opt->flags & BKF_OPT_MAX_OPEN) ? 0.5 : 0));
        *hi = m >= 1.8e19 ? SIZE_MAX : m < 0 ? 0 : (size_t)m;
    }
}

const char *bkf_option_describe(const bkf_option *opt, char *buf, size_t size)
{
    char r[96], list[256];
    size_t lo, hi;
    switch (opt->type) {
    case BKF_OPT_SWITCH: snprintf(buf, size, "no value"); break;
    case BKF_OPT_DOUBLE:
        bounds_text(opt, r, sizeof r);
        snprintf(buf, size, "a number%s%s", *r ? " " : "", r);
        break;
    case BKF_OPT_COUNT:
        count_bounds(opt, &lo, &hi);
        snprintf(buf, size, "an integer in [%zu, %zu]", lo, hi);
        break;
    case BKF_OPT_DOUBLE_LIST:
        bounds_text(opt, r, sizeof r);
        snprintf(buf, size, "V, V1,V2,... or A:B:N%s%s", *r ? ", each " : "", r);
        break;
    case BKF_OPT_COUNT_LIST:
        count_bounds(opt, &lo, &hi);
        snprintf(buf, size, "K, K1,K2,... or A:B:N, integers in [%zu, %zu]", lo, hi);
        break;
    case BKF_OPT_CHOICE:
        choice_list(opt->choices, list, sizeof list);
        snprintf(buf, size, "one of %s", list);
        break;
    case BKF_OPT_TEXT: snprintf(buf, size, "a non-empty text"); break;
    case BKF_OPT_SEED: snprintf(buf, size, "an integer in [0, 18446744073709551615]"); break;
    case BKF_OPT_CUSTOM: snprintf(buf, size, "%s", opt->form ? opt->form : "a value"); break;
    }
    return buf;
}

static int list_apply(const bkf_option *opt, void *spec, const char *text, const char *prefix,
                      bkf_error *err)
{
    char a[32], r[96], t[72];
    int integer = opt->type == BKF_OPT_COUNT_LIST;
    int geometric = (opt->flags & BKF_OPT_GEOMETRIC) ||
                    ((opt->flags & BKF_OPT_LOG_SWITCH) &&
                     *(const int *)((const char *)spec + opt->log_offset));
    bkf_list list;
    int s = bkf_list_parse(text, geometric, integer, opt->max_count, prefix, opt->name, &list, err);
    if (s) return s;
    size_t lo = 0, hi = 0;
    if (integer) count_bounds(opt, &lo, &hi);
    for (size_t i = 0; i < list.count; i++) {
        double x = list.values[i];
        int ok = integer ? (x >= (double)lo && x <= (double)hi) : in_bounds(opt, x);
        if (ok) continue;
        if (integer)
            snprintf(r, sizeof r, "in [%zu, %zu]", lo, hi);
        else
            bounds_text(opt, r, sizeof r);
        s = bkf_error_set(err, BKF_EINPUT, "%s%s: %s = %s%s%s%s is not %s", prefix, opt->name,
                          opt->name, bkf_format_number(x, a, sizeof a),
                          list.count > 1 ? " (in '" : "",
                          list.count > 1 ? bkf_option_shown(text, t, sizeof t) : "",
                          list.count > 1 ? "')" : "", r);
        bkf_list_free(&list);
        return s;
    }
    bkf_list *field = (bkf_list *)((char *)spec + opt->offset);
    bkf_list_free(field);
    *field = list;
    return BKF_OK;
}

int bkf_option_apply(const bkf_option *opt, void *spec, const char *text, const char *prefix,
                     bkf_error *err)
{
    char a[72], r[96];
    char *field = (char *)spec + opt->offset;
    if (!prefix) prefix = "";
    if (opt->type != BKF_OPT_SWITCH && !text)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: missing value (expected %s)", prefix,
                             opt->name, bkf_option_describe(opt, r, sizeof r));
    int s;
    switch (opt->type) {
    case BKF_OPT_SWITCH:
        if (text) return bkf_error_set(err, BKF_EINPUT, "%s%s: takes no value", prefix, opt->name);
        *(int *)field = 1;
        return BKF_OK;
    case BKF_OPT_DOUBLE: {
        double x = 0;
        if ((s = bkf_option_parse_double(text, prefix, opt->name, &x, err))) return s;
        if (!in_bounds(opt, x))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: %s is not %s", prefix, opt->name,
                                 bkf_option_shown(text, a, sizeof a),
                                 bounds_text(opt, r, sizeof r));
        *(double *)field = x;
        return BKF_OK;
    }
    case BKF_OPT_COUNT: {
        size_t lo, hi, k = 0;
        count_bounds(opt, &lo, &hi);
        if ((s = bkf_option_parse_count(text, lo, hi, prefix, opt->name, &k, err))) return s;
        *(size_t *)field = k;
        return BKF_OK;
    }
    case BKF_OPT_DOUBLE_LIST:
    case BKF_OPT_COUNT_LIST: return list_apply(opt, spec, text, prefix, err);
    case BKF_OPT_CHOICE: {
        int k = 0;
        if ((s = bkf_option_parse_choice(text, opt->choices, prefix, opt->name, &k, err)))
            return s;
        *(int *)field = k;
        return BKF_OK;
    }
    case BKF_OPT_TEXT:
        if (!*text) return bkf_error_set(err, BKF_EINPUT, "%s%s: the value is empty", prefix,
                                         opt->name);
        *(const char **)field = text;
        return BKF_OK;
    case BKF_OPT_SEED: {
        uint64_t v;
        if (!read_unsigned(text, UINT64_MAX, &v))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not %s", prefix, opt->name,
                                 bkf_option_shown(text, a, sizeof a),
                                 bkf_option_describe(opt, r, sizeof r));
        *(uint64_t *)field = v;
        return BKF_OK;
    }
    case BKF_OPT_CUSTOM: {
        bkf_error e = {0};
        if (!opt->set) return bkf_error_set(err, BKF_EINPUT, "%s%s: no setter", prefix, opt->name);
        s = opt->set(spec, text, &e);
        if (s) return bkf_error_set(err, s, "%s%s: %s", prefix, opt->name, e.message);
        return BKF_OK;
    }
    }
    return bkf_error_set(err, BKF_EINPUT, "%s%s: unknown option type", prefix, opt->name);
}

void bkf_option_free_lists(const bkf_option *table, size_t n, void *spec)
{
    if (!spec) return;
    for (size_t i = 0; i < n; i++)
        if (table[i].type == BKF_OPT_DOUBLE_LIST || table[i].type == BKF_OPT_COUNT_LIST)
            bkf_list_free((bkf_list *)((char *)spec + table[i].offset));
}

# The manual page (man(7) roff) of one `bkfront ... --help` text, so that
# the installed pages are the help itself and cannot drift from it (the
# Makefile runs this at build time; tests/python/test_man.py renders them).
#   awk -v page=bkfront-speeds -v summary='...' -v version=0.1.0 -f man.awk
# The help's layout (args.h): the "usage:" paragraph, then paragraphs of
# text at column 0, and lists under a "word:" line whose entries are
# "  TAG  text" (TAG: an option or a column, two or more spaces before its
# text, or alone on its line) continued by deeper-indented lines.  A list
# under options:, subcommands: or columns: becomes that section; any other
# indented line (a formula) is kept as it is.

function esc(s) {
    gsub(/\\/, "\\e", s)
    gsub(/-/, "\\-", s)
    if (s ~ /^[.']/) s = "\\&" s
    return s
}

# An entry line: exactly two spaces, then a non-space.
function is_entry(s) { return s ~ /^  [^ ]/ }

# The column where the entries' texts start in the list after line i: the
# most common end of a tag's gap (a tag longer than it pushes its text
# further, or leaves a single space before it).
function list_column(i,    j, t, best, c, cnt) {
    best = 0
    for (j = i + 1; j <= n && (is_entry(line[j]) || line[j] ~ /^   /); j++) {
        if (!is_entry(line[j])) continue
        t = substr(line[j], 3)
        if (match(t, /[^ ]   */)) {
            c = RSTART + RLENGTH + 2
            cnt[c]++
            if (!best || cnt[c] > cnt[best]) best = c
        }
    }
    return best
}

function out(s) { print s }

BEGIN { section = "SYNOPSIS"; n = 0 }
{ line[++n] = $0 }

END {
    upper = toupper(page)
    out(".TH " esc(upper) " 1 \"\" \"bkfront " version "\" \"bkfront manual\"")
    out(".SH NAME")
    out(esc(page) " \\- " esc(summary))
    out(".SH SYNOPSIS")
    out(".nf")
    i = 1
    # the usage paragraph, "usage: " and its alignment removed
    for (; i <= n && line[i] != ""; i++) {
        s = line[i]
        sub(/^usage: /, "", s)
        sub(/^       /, "", s)
        out(esc(s))
    }
    out(".fi")
    out(".SH DESCRIPTION")
    mode = "text" # text, list, pre
    for (; i <= n; i++) {
        s = line[i]
        if (s == "") {
            if (mode == "pre") out(".fi")
            mode = "blank"
            continue
        }
        next_entry = (i < n && is_entry(line[i + 1]))
        if (s ~ /^[^ ].*:$/ && next_entry) {
            if (mode == "pre") out(".fi")
            if (mode == "text") {
                # the last line of a paragraph ("... Columns:")
                section = ""
                out(esc(s))
            } else if (s ~ /^[a-z]+:$/) {
                section = toupper(substr(s, 1, length(s) - 1))
                out(".SH " section)
            } else {
                section = ""
                out(".PP")
                out(esc(s))
            }
            mode = "list"
            col = list_column(i)
            continue
        }
        if (mode == "list" && is_entry(s)) {
            t = substr(s, 3)
            if (match(t, /[^ ]   */)) {
                tag = substr(t, 1, RSTART)
                text = substr(t, RSTART + RLENGTH)
            } else if (col && substr(s, col - 1, 1) == " " && substr(s, col, 1) != " " &&
                       substr(s, col - 2, 1) != " ") {
                tag = substr(s, 3, col - 4)
                text = substr(s, col)
            } else {
                tag = t
                text = ""
            }
            out(".TP")
            if (section == "SUBCOMMANDS") out("\\fBbkfront\\-" esc(tag) "\\fR(1)")
            else out("\\fB" esc(tag) "\\fR")
            if (text != "") out(esc(text))
            continue
        }
        if (mode == "list" && s ~ /^   /) {
            sub(/^ +/, "", s)
            if (s ~ /^default /) out(".br")
            out(esc(s))
            continue
        }
        if (s ~ /^ /) {
            if (mode != "pre") {
                out(".nf")
                mode = "pre"
            }
            out(esc(s))
            continue
        }
        if (mode == "pre") out(".fi")
        if (mode != "text") out(".PP")
        mode = "text"
        out(esc(s))
    }
    if (mode == "pre") out(".fi")
    if (page != "bkfront") {
        out(".SH SEE ALSO")
        out("\\fBbkfront\\fR(1)")
    }
}

"""Every relative link of the manual resolves: in the source tree (README,
CONTRIBUTING, docs/) and, through dead_links(), in the installed tree
(test_install.py).  A link resolves when its file exists and, for a
markdown target with #anchor, the anchor is one of its headings (GitHub's
slugs) or an explicit <a name/id>.  Links inside code blocks are code."""
import glob
import os
import re

from conftest import SOURCE

LINK = re.compile(r"\]\(([^)\s]+)\)")
HEADING = re.compile(r"#{1,6}\s+(.*?)\s*#*\s*$")


def _without_blocks(text):
    return re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)


def _without_code(text):
    return re.sub(r"`[^`\n]*`", "", _without_blocks(text))


def anchors(path):
    """The anchors a markdown page defines: GitHub's heading slugs (with
    -1, -2 for repeats) and explicit <a name=...> / id=..."""
    out, seen = set(), {}
    text = open(path, encoding="utf-8").read()
    for line in _without_blocks(text).splitlines():
        m = HEADING.match(line)
        if not m:
            continue
        slug = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else "%s-%d" % (slug, n))
    out.update(re.findall(r'<a (?:name|id)="([^"]+)"', text))
    return out


def pages(root):
    """The markdown pages of a manual tree: README, CONTRIBUTING, docs/."""
    found = [os.path.join(root, p) for p in ("README.md", "CONTRIBUTING.md")]
    found += glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True)
    return [p for p in found if os.path.exists(p)]


def dead_links(root):
    """(page, link) for every relative link of the tree at root that does
    not resolve."""
    dead = []
    cache = {}
    for page in pages(root):
        text = _without_code(open(page, encoding="utf-8").read())
        for link in LINK.findall(text):
            if re.match(r"[a-z][a-z0-9+.-]*:", link):  # http:, mailto:
                continue
            path, _, anchor = link.partition("#")
            target = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
            if not os.path.exists(target):
                dead.append((os.path.relpath(page, root), link))
            elif anchor and target.endswith(".md"):
                if target not in cache:
                    cache[target] = anchors(target)
                if anchor not in cache[target]:
                    dead.append((os.path.relpath(page, root), link))
    return dead


def test_the_source_manual_has_no_dead_link():
    assert len(pages(SOURCE)) > 20
    assert dead_links(SOURCE) == []


def test_the_checker_sees_a_dead_link_and_a_dead_anchor(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("# Top\n\n## A b, c\n[ok](docs/x.md#sec) [ok](#a-b-c)\n"
                                        "[bad](docs/y.md) [bad](docs/x.md#nope) `[code](z.md)`\n")
    (tmp_path / "docs" / "x.md").write_text("# Sec\n[up](../README.md#top)\n")
    assert sorted(dead_links(str(tmp_path))) == [("README.md", "docs/x.md#nope"),
                                                 ("README.md", "docs/y.md")]


def _section(text, heading):
    return text.split(heading + "\n", 1)[1].split("\n## ", 1)[0]


def test_every_command_page_is_listed():
    """The README's Documentation list and the manual's index name every
    page of docs/cli/."""
    cli_pages = {os.path.basename(p) for p in glob.glob(os.path.join(SOURCE, "docs", "cli", "*.md"))}
    assert len(cli_pages) >= 13
    readme = open(os.path.join(SOURCE, "README.md"), encoding="utf-8").read()
    listed = set(re.findall(r"\(docs/cli/([a-z_]+\.md)\)", _section(readme, "## Documentation")))
    assert listed == cli_pages
    index = open(os.path.join(SOURCE, "docs", "index.md"), encoding="utf-8").read()
    assert set(re.findall(r"\(cli/([a-z_]+\.md)[)#]", index)) == cli_pages

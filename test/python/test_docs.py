#!/usr/bin/python3
"""The documentation guides a newcomer who has only the repository: every relative link and every repository path
named in README.md and docs/*.md exists in the repository, no link leaves it (except into the shared data folder
given beside the checkout), every #anchor names a heading, and README.md links every page of docs/."""
import glob
import os
import re
import unittest

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
# The only place outside the repository that a link may point to: the data folder beside the checkout
# (../shared/data), whose files the tools take as input arguments.
SHARED_DATA_DIR = os.path.join(os.path.dirname(PACKAGE_DIR), "shared", "data")

# A backticked word is taken for a repository path when it starts with one of these folders (or is one of the
# top-level files), e.g. `scripts/test.sh`, `config/layout.yaml`, `src/<subsystem>/`.
TOP_FOLDERS = ("config", "docs", "include", "launch_files", "msg", "scripts", "src", "srv", "test", "worlds")
TOP_FILES = ("README.md", "CMakeLists.txt", "package.xml", "setup.py")
# Characters that start a placeholder inside a path (`test/<subsystem>/`, `worlds/*.xml`): only the folders before
# it are checked.
PLACEHOLDER = re.compile(r"[<*{$\[]|\.\.\.")

FENCE = re.compile(r"^\s*(```|~~~)")
INLINE_CODE = re.compile(r"`([^`\n]+)`")
LINK = re.compile(r"!?\[([^\]]*)\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
CODE_PATH = re.compile(r"(?:^|(?<=[\s'\"=(]))((?:%s)/[^\s'\"`),;|]*)" % "|".join(TOP_FOLDERS))


def documents():
    """README.md and every docs/*.md, as paths relative to the repository."""
    docs = sorted(os.path.relpath(path, PACKAGE_DIR) for path in glob.glob(os.path.join(PACKAGE_DIR, "docs", "*.md")))
    return ["README.md"] + docs


def read(document):
    with open(os.path.join(PACKAGE_DIR, document), encoding="utf-8") as stream:
        return stream.read()


def split_code(text):
    """(prose, code): the text with fenced code blocks blanked out, and the fenced blocks' lines alone (each keeps
    its line number: both have as many lines as the text)."""
    prose, code = [], []
    in_fence = False
    for line in text.split("\n"):
        if FENCE.match(line):
            in_fence = not in_fence
            prose.append("")
            code.append("")
        elif in_fence:
            prose.append("")
            code.append(line)
        else:
            prose.append(line)
            code.append("")
    return "\n".join(prose), "\n".join(code)


def line_of(text, offset):
    return text.count("\n", 0, offset) + 1


def slug(heading):
    """GitHub's anchor of a heading: links and code marks dropped, lower case, punctuation removed, spaces to '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading).replace("`", "").lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(document):
    """Every heading anchor of a Markdown document (repeated headings get -1, -2, ... as on GitHub)."""
    prose, _ = split_code(read(document))
    seen = {}
    result = set()
    for line in prose.split("\n"):
        match = HEADING.match(line)
        if not match:
            continue
        base = slug(match.group(2))
        count = seen.get(base, 0)
        seen[base] = count + 1
        result.add(base if count == 0 else "%s-%d" % (base, count))
    return result


def links(document):
    """(line, target) of every Markdown link and image outside code."""
    prose, _ = split_code(read(document))
    prose = INLINE_CODE.sub(lambda match: " " * len(match.group(0)), prose)
    return [(line_of(prose, match.start()), match.group(2)) for match in LINK.finditer(prose)]


def checked_part(path):
    """The part of a named path that can be checked: up to its first placeholder, whole folders only."""
    match = PLACEHOLDER.search(path)
    if match:
        path = path[:match.start()]
        path = path[:path.rfind("/") + 1]
    return path


def repository_paths(document):
    """(line, path, part to check) of every repository path named in inline code or in code blocks."""
    text = read(document)
    prose, code = split_code(text)
    found = []
    for match in INLINE_CODE.finditer(prose):
        words = match.group(1).split()
        word = words[0].rstrip(".,;:)") if words else ""
        if word in TOP_FILES or ("/" in word and word.split("/")[0] in TOP_FOLDERS):
            found.append((line_of(prose, match.start()), word))
    for match in CODE_PATH.finditer(code):
        found.append((line_of(code, match.start()), match.group(1).rstrip(".,;:")))
    return [(line, path, checked_part(path)) for line, path in sorted(found)]


def inside(path, folder):
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder + os.sep)


class DocumentTest(unittest.TestCase):
    def check(self, problems):
        if problems:
            self.fail("%d problem(s):\n" % len(problems) + "\n".join(problems))


class DocumentLinks(DocumentTest):
    def test_relative_links_name_files_in_the_repository(self):
        problems = []
        for document in documents():
            for line, target in links(document):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                    continue  # a URL, or an anchor in the same document (test_anchors_name_headings)
                path = os.path.normpath(os.path.join(PACKAGE_DIR, os.path.dirname(document), target.split("#")[0]))
                if not inside(path, PACKAGE_DIR):
                    if not inside(path, SHARED_DATA_DIR):
                        problems.append("%s:%d: link '%s' points outside the repository" % (document, line, target))
                elif not os.path.exists(path):
                    problems.append("%s:%d: link '%s' names no file in the repository" % (document, line, target))
        self.check(problems)

    def test_anchors_name_headings(self):
        problems = []
        for document in documents():
            for line, target in links(document):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or "#" not in target:
                    continue
                file_part, anchor = target.split("#", 1)
                linked = os.path.normpath(os.path.join(os.path.dirname(document), file_part)) if file_part else document
                if not linked.endswith(".md") or not os.path.isfile(os.path.join(PACKAGE_DIR, linked)):
                    continue  # a missing file is test_relative_links_name_files_in_the_repository's problem
                if anchor not in anchors(linked):
                    problems.append("%s:%d: link '%s': %s has no heading with the anchor '#%s'"
                                    % (document, line, target, linked, anchor))
        self.check(problems)

    def test_readme_links_every_document(self):
        linked = set()
        for _, target in links("README.md"):
            linked.add(os.path.normpath(target.split("#")[0]))
        self.check(["README.md does not link %s" % document for document in documents()[1:] if document not in linked])

    def test_no_document_sends_readers_to_files_outside_the_repository(self):
        problems = []
        for document in documents():
            for number, line in enumerate(read(document).split("\n"), 1):
                if "METHOD.md" in line:
                    problems.append("%s:%d: names METHOD.md, which is not in the repository (see docs/method.md)"
                                    % (document, number))
        self.check(problems)


class DocumentPaths(DocumentTest):
    def test_named_repository_paths_exist(self):
        problems = []
        for document in documents():
            for line, path, checked in repository_paths(document):
                if not os.path.exists(os.path.join(PACKAGE_DIR, checked)):
                    what = "" if checked == path else " (its part %s)" % checked
                    problems.append("%s:%d: `%s`%s is not in the repository" % (document, line, path, what))
        self.check(problems)


class DocumentedLimits(DocumentTest):
    def test_the_limits_table_gives_the_values_of_the_code(self):
        """docs/file_formats.md#limits lists every constant of input_limits.h with its value."""
        header = read(os.path.join("include", "hidden_rooms", "common", "input_limits.h"))
        code = {name: float(value) for name, value in
                re.findall(r"constexpr (?:double|int) (kMax\w+) = ([0-9.e]+);", header)}
        table = {name: float(value) for name, value in
                 re.findall(r"^\| `(kMax\w+)` \| ([0-9.e]+) \|", read(os.path.join("docs", "file_formats.md")), re.M)}
        self.assertGreaterEqual(len(code), 5)
        self.assertEqual(table, code)


if __name__ == "__main__":
    unittest.main()

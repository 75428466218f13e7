"""Checks of a page that must stand alone (the report's and the stress suite's
index.html): it parses with the standard library's HTML parser, its elements nest
(every end tag closes the element opened last), and it references no external
resource: no attribute that loads something (src, href other than a #fragment, srcset,
data, poster, action, formaction, background, xlink:href), no <link>, <script>,
<iframe>, <object> or <embed>, no url(...) or @import in a style. Pure: text in,
problems out."""

from __future__ import annotations

import re
from html.parser import HTMLParser

# elements without an end tag (HTML5) and SVG's self-closing ones are handled by
# handle_startendtag
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta",
        "param", "source", "track", "wbr"}
LOADING_ATTRIBUTES = {"src", "srcset", "data", "poster", "action", "formaction",
                      "background", "xlink:href", "href"}
LOADING_ELEMENTS = {"link", "script", "iframe", "object", "embed", "frame", "audio",
                    "video", "img", "source"}
CSS_LOADS = re.compile(r"url\s*\(|@import", re.IGNORECASE)


class _Checker(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.problems: list[str] = []
        self.counts: dict[str, int] = {}
        self.in_style = False

    def _where(self) -> str:
        line, col = self.getpos()
        return f"line {line}, column {col}"

    def _attributes(self, tag: str, attrs) -> None:
        self.counts[tag] = self.counts.get(tag, 0) + 1
        if tag in LOADING_ELEMENTS:
            self.problems.append(f"<{tag}> at {self._where()}: loads or embeds a resource")
        for name, value in attrs:
            value = value or ""
            if name in LOADING_ATTRIBUTES and not (name == "href" and value.startswith("#")):
                self.problems.append(f"{name}=\"{value}\" on <{tag}> at {self._where()}")
            if name == "style" and CSS_LOADS.search(value):
                self.problems.append(f"style loads a resource at {self._where()}: {value}")

    def handle_starttag(self, tag, attrs):
        self._attributes(tag, attrs)
        if tag == "style":
            self.in_style = True
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self._attributes(tag, attrs)

    def handle_endtag(self, tag):
        if tag == "style":
            self.in_style = False
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            open_tag = self.stack[-1] if self.stack else "nothing"
            self.problems.append(f"</{tag}> at {self._where()} closes <{open_tag}>")
            if tag in self.stack:
                while self.stack and self.stack.pop() != tag:
                    pass
            return
        self.stack.pop()

    def handle_data(self, data):
        if self.in_style and CSS_LOADS.search(data):
            self.problems.append(f"<style> loads a resource at {self._where()}")


def check_page(text: str) -> tuple[list[str], dict[str, int]]:
    """The problems of a standalone page and how many of each element it has."""
    checker = _Checker()
    checker.feed(text)
    checker.close()
    problems = list(checker.problems)
    if checker.stack:
        problems.append(f"unclosed at the end: {checker.stack}")
    if not text.lstrip().lower().startswith("<!doctype html>"):
        problems.append("no <!DOCTYPE html>")
    return problems, checker.counts

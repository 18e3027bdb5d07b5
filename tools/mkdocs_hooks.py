"""MkDocs hook: the docstrings' Sphinx roles (:class:`X`, :func:`f`, ...) shown as plain code."""

import re

ROLE = re.compile(r":(?:class|func|mod|meth|data|attr|exc):(?=<code>)")


def on_page_content(html, **kwargs):
    return ROLE.sub("", html)

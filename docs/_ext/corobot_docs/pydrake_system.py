"""`.. pydrake_system::`, as Drake's docs write a system's ports in a docstring: here shown as
the block it is (name, input and output ports), where Drake's own docs draw a box."""

from __future__ import annotations

from docutils import nodes
from docutils.parsers.rst import Directive


class PydrakeSystem(Directive):
    has_content = True

    def run(self):
        text = "\n".join(self.content)
        return [nodes.literal_block(text, text, language="yaml")]

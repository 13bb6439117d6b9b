"""XML that parses whatever text an implementation sends: the JUnit writers' one way out.

A driver's name, a server's log line or a rule it invents may hold characters XML 1.0 cannot carry
(control characters, a lone surrogate from a JSON ``\\udc80`` escape, U+FFFE): written as they are,
the report does not parse, or cannot even be encoded.  :func:`xml_safe` writes each such character
as ``\\uXXXX`` (visible, and never mistaken for the character itself), and :func:`xml_document`
applies it to every attribute and text of a tree before the tree is written.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

__all__ = ["xml_document", "xml_safe"]

#: The characters XML 1.0 has no place for (besides tab, newline and carriage return).
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def xml_safe(text: str) -> str:
    """``text`` with every character XML 1.0 cannot hold written as ``\\uXXXX``."""
    return _NOT_XML.sub(lambda found: f"\\u{ord(found.group()):04x}", text)


def xml_document(root: ET.Element) -> str:
    """``root`` as an XML document (declaration, indented), every attribute and text made safe."""
    for element in root.iter():
        element.attrib = {xml_safe(name): xml_safe(value) for name, value in element.attrib.items()}
        if element.text is not None:
            element.text = xml_safe(element.text)
        if element.tail is not None:
            element.tail = xml_safe(element.tail)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"

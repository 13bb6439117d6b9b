"""Did-you-mean for a name that is not on a robot's map, in time bounded whatever the map or the name.

The names are indexed once, by their character trigrams; a question visits the
postings of its rarest trigrams first, up to :data:`_VISITS` of them, and asks
:func:`difflib.get_close_matches` (the judge of "close") about the few names
sharing the most trigrams with it.  A name longer than :data:`LONGEST_QUESTION`
gets no suggestion: nothing on a map is that close to it, and its trigrams would
cost more than they tell.
"""

from __future__ import annotations

import difflib
import heapq
from collections import Counter
from collections.abc import Iterable

__all__ = ["LONGEST_QUESTION", "Suggestions"]

#: The longest name a suggestion is looked for (in characters).
LONGEST_QUESTION = 64
#: The most postings one question visits.
_VISITS = 4_096
#: The names sharing the most trigrams that difflib compares with the question.
_CANDIDATES = 16


def _trigrams(name: str) -> set[str]:
    padded = f"  {name} "
    return {padded[index : index + 3] for index in range(len(padded) - 2)}


class Suggestions:
    """The names of a map, indexed for :meth:`closest`."""

    def __init__(self, names: Iterable[str]) -> None:
        self._names = list(names)
        postings: dict[str, list[int]] = {}
        for number, name in enumerate(self._names):
            for gram in _trigrams(name):
                postings.setdefault(gram, []).append(number)
        self._postings = postings

    def closest(self, name: str) -> str | None:
        """The indexed name closest to ``name`` (difflib's ratio of at least 0.6), or ``None``."""
        if len(name) > LONGEST_QUESTION or not self._names:
            return None
        found = [self._postings[gram] for gram in _trigrams(name) if gram in self._postings]
        shared: Counter[int] = Counter()
        visits = _VISITS
        for posting in sorted(found, key=len):  # the rarest trigrams tell the most
            if len(posting) > visits:
                break
            shared.update(posting)
            visits -= len(posting)
        best = heapq.nlargest(_CANDIDATES, shared.items(), key=lambda item: (item[1], -item[0]))
        close = difflib.get_close_matches(name, [self._names[number] for number, _ in best], n=1)
        return close[0] if close else None

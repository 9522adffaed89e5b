"""The files pinrate writes and reads back: written whole or not at all
(:mod:`~pinrate.files.replace`), read without trust (:mod:`~pinrate.files.npz`, once the file
and every member's header pass the checks and caps of :mod:`~pinrate.files.npz_members`)."""

from .npz import MAX_LOAD_BYTES, NUMBERS, Npz, open_npz
from .npz_members import DEFLATE_RATIO, MAX_MEMBERS
from .replace import replace_file

__all__ = ["DEFLATE_RATIO", "MAX_LOAD_BYTES", "MAX_MEMBERS", "NUMBERS", "Npz", "open_npz", "replace_file"]

"""Bracket words, the Hall basis, Lie brackets, fields as polynomials, words' values at a point."""

from nilpotent.core.lie.brackets import Word as Word
from nilpotent.core.lie.brackets import bracket as bracket
from nilpotent.core.lie.brackets import format_word as format_word
from nilpotent.core.lie.brackets import hall_basis as hall_basis
from nilpotent.core.lie.brackets import lie_derivative as lie_derivative
from nilpotent.core.lie.brackets import parse_word as parse_word
from nilpotent.core.lie.brackets import word_field as word_field
from nilpotent.core.lie.brackets import word_length as word_length
from nilpotent.core.lie.polynomial_fields import PolynomialFields as PolynomialFields
from nilpotent.core.lie.polynomial_fields import polynomial_fields as polynomial_fields
from nilpotent.core.lie.word_values import WordValues as WordValues

__all__ = [
    "PolynomialFields", "Word", "WordValues", "bracket", "format_word", "hall_basis",
    "lie_derivative", "parse_word", "polynomial_fields", "word_field", "word_length",
]

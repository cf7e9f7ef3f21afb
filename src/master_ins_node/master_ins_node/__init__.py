"""Ship master INS solution: truth plus a master INS error model."""

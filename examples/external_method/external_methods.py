"""Python side of the external method example: ``lib.factorial(n)``."""


def factorial(n: int) -> int:
    """n! for a non-negative integer."""
    result = 1
    for value in range(2, n + 1):
        result *= value
    return result

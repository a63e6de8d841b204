"""What the operators catch from the core, and how they say it.

The core's errors arrive as ValueError (bad input), OSError (files),
RuntimeError (PenumbraError, Cancelled) and MemoryError (std::bad_alloc on
any thread): each is reported, never left to escape an operator as a
traceback."""

CORE_ERRORS = (ValueError, OSError, RuntimeError, MemoryError)


def describe(error):
    """The report for `error`: its own message, or for running out of memory
    what to do about it."""
    if isinstance(error, MemoryError):
        return (f"out of memory ({error or 'MemoryError'}): lower what sizes the work (rays, frames, resolution, "
                "light count, lookup size) or free memory, then try again")
    return str(error)

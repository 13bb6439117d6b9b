"""A structure-aware fuzzer of every dynevent entry point that parses, restores or takes outside input."""

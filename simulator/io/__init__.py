"""Input and output: FOLD files and the self-contained HTML result viewer."""

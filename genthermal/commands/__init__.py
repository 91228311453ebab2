"""The sub-commands of ``genthermal``, one module each (``register`` adds the parser, ``run`` does the work).

Reference: docs/guide/cli.md.
"""

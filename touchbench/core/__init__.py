"""The bottom layer: what every other part of touchbench may use.

Errors, the registry pattern, paths, hashing, atomic file writes, package
versions, name suggestions and small introspection / threading helpers.
Nothing here imports any other touchbench package.
"""

"""Solids and machining files of a swept pair: one module per file format.

``stl`` (binary STL), ``step`` (STEP through gmsh/OpenCASCADE), ``csvfile``, ``dxf``,
``ply`` (profile CSV and DXF, point clouds as CSV and PLY), ``cloud`` (the points on a
flank), ``cutter`` (form-cutter profile); ``solids``
builds the flank grids and triangle meshes they write, ``driver`` runs what a case's
[export] section asks for, ``settings`` reads that section.  Nothing is imported
here: reading the settings must not load the meshing libraries.
"""

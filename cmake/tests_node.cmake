# Tests of the node area.

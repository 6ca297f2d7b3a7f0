# Tests of the devices area.

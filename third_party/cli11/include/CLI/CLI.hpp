// The vendored CLI11 under the name the sources include (<CLI/CLI.hpp>); see ../../README.md.
#pragma once
#include "../../CLI11.hpp"

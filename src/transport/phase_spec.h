// Phase functions from short command-line specs: `iso`, `hg:G`, `dhg:G1,G2,W`, `gauss:THETA2`,
// `mie:NAME` (the table phase/NAME.csv under $NIMBUS_DATA_DIR, else under the installed share/nimbus,
// else data/phase/NAME.csv of the source tree) or `mie:PATH` (a path with '/' or ending in .csv: that file),
// `ff:N,MU` (Fournier-Forand, refractive index N, Junge slope MU) or `ffb:B` (Fournier-Forand with the
// backscatter fraction B on Mobley et al. 2002's curve n = 1.01 + 0.1542 (mu - 3)); media/fournier_forand.h.
#pragma once

#include <string>
#include <vector>

#include "media/phase.h"

namespace nimbus {

// Comma-separated finite numbers ("1,3,10"); errors start with `what` and quote the bad item.
std::vector<double> parse_number_list(const std::string& what, const std::string& list);

// Throws nimbus::Error naming the spec on anything malformed or out of range.
Phase parse_phase_spec(const std::string& spec);

// Loads a two-column CSV table (theta in radians from 0 to pi, value per sr; a header line and lines
// starting with '#' are skipped) as a normalised TabulatedPhase.
TabulatedPhase load_phase_table(const std::string& name, const std::string& path);

// The directory holding phase tables: $NIMBUS_DATA_DIR/phase if set, else the installed
// PREFIX/share/nimbus/phase when it exists (PREFIX: the program's bin/.., then the configured install
// prefix), else NIMBUS_SOURCE_DIR/data/phase.
std::string phase_table_dir();

// Whether `name` names a table of phase_table_dir() (letters, digits, '_', '-', '.', not starting with '.'):
// never a path, so it cannot leave that directory.
bool is_phase_table_name(const std::string& name);

}  // namespace nimbus

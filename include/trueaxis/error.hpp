// trueaxis — the one exception type of the library.
//
// Every recoverable failure (malformed file, unobservable layout, invalid option) throws
// trueaxis::Error. The CLI turns it into a one-line message and a non-zero exit code; the Python
// module turns it into trueaxis.Error (a ValueError). Messages that concern a file start with
// "path:line:column: " so that editors and users can jump to the spot.
#pragma once

#include <stdexcept>
#include <string>

namespace trueaxis {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace trueaxis

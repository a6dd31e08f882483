// The one exception type for a user's mistake (a bad file, config or argument). Its own small
// header so that every library reports input problems the same way without including mesh.h.
#pragma once

#include <stdexcept>

namespace rtwall {

// A user-facing input problem (bad file, bad config, bad argument). what() is one line:
// "<file>:<line or offset>: <what is wrong>", or "<file>: <what is wrong>" where no place is known.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace rtwall

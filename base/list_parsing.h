#ifndef SPINESIM_BASE_LIST_PARSING_H
#define SPINESIM_BASE_LIST_PARSING_H

// The one reader of number lists in parameters ("1, 2.5, -3"), points and pre-crack corner
// lists ("x,y; x,y"). Every value must be a finite number written in full: "1, abc", "1,,2"
// and "2x" are InvalidInput naming the parameter, never a silent 0.

#include <string>
#include <vector>

namespace spinesim {

// Comma-separated numbers. An empty (or all-blank) text gives an empty list when
// `allow_empty`, else InvalidInput. `where` names the parameter, e.g. "Geometry/Lengths".
std::vector<double> parse_number_list(const std::string& text, const std::string& where,
                                      bool allow_empty = false);

// The same with a fixed count (`count` numbers, e.g. one per dimension); InvalidInput naming
// the count otherwise. `unit` is appended to the allowed form, e.g. "[m]".
std::vector<double> parse_numbers(const std::string& text, const std::string& where,
                                  unsigned int count, const std::string& unit = "");

// ';'-separated points of `dim` comma-separated numbers each ("x,y; x,y"), flattened.
// `n_points` = 0 accepts any number of points (at least one).
std::vector<double> parse_point_list(const std::string& text, const std::string& where,
                                     unsigned int dim, unsigned int n_points = 0);

// A pre-crack: a 2-D segment "x1,y1; x2,y2" (4 numbers) or a 3-D planar quadrilateral of four
// corners (12 numbers), flattened. Empty text gives an empty list (an unused slot).
std::vector<double> parse_crack_corners(const std::string& text, const std::string& where,
                                        unsigned int dim);

} // namespace spinesim

#endif

#include "fem/mesh_file_check.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace spinesim::fem {

namespace {

// Numbers larger than this many per byte of file cannot be dense node or element numbers:
// a real file spends at least a few bytes per node. A generous bound that still keeps every
// array GridIn sizes by a number from the file within a small multiple of the file's size.
constexpr double max_number_per_byte = 4.0;

class LineReader {
 public:
  LineReader(std::istream& in, const std::string& name, std::size_t bytes)
      : file_(name), in_(in), bytes_(static_cast<double>(std::max<std::size_t>(bytes, 1))) {}
  bool next(std::string& line) {
    if (!std::getline(in_, line))
      return false;
    ++number_;
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    return true;
  }
  std::string need(const std::string& what) {
    std::string line;
    if (!next(line))
      fail("the file ends early", what);
    return line;
  }
  [[noreturn]] void fail(const std::string& problem, const std::string& expected) const {
    throw InvalidInput("Mesh file", file_ + ":" + std::to_string(number_) + ": " + problem,
                       expected);
  }
  double bytes() const { return bytes_; }
  unsigned long line() const { return number_; }

 private:
  std::string file_;
  std::istream& in_;
  double bytes_ = 1;
  unsigned long number_ = 0;
};

// Whitespace- (and optionally comma-) separated tokens of a line.
std::vector<std::string> tokens(const std::string& line, bool commas) {
  std::string s = line;
  if (commas)
    std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string t; in >> t;)
    out.push_back(t);
  return out;
}

bool is_integer(const std::string& t, long long& value) {
  if (t.empty())
    return false;
  errno = 0;
  char* end = nullptr;
  value = std::strtoll(t.c_str(), &end, 10);
  return errno == 0 && end == t.c_str() + t.size();
}

bool is_real(const std::string& t) {
  if (t.empty())
    return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  return errno == 0 && end == t.c_str() + t.size() && std::isfinite(v);
}

// The first word of a line that must have one.
std::string first_word(LineReader& r, const std::string& line, const std::string& what) {
  const auto t = tokens(line, false);
  if (t.empty())
    r.fail("empty line", what);
  return t[0];
}

// A count or a node/element number read from the file, bounded by what the file can hold.
long long bounded(LineReader& r, const std::string& token, const std::string& what) {
  long long v = 0;
  if (!is_integer(token, v) || v < 0)
    r.fail("'" + token + "' is not a " + what, "a non-negative whole number");
  if (static_cast<double>(v) > max_number_per_byte * r.bytes() + 1000)
    r.fail(what + " " + token + " is larger than a file of " +
               std::to_string(static_cast<long long>(r.bytes())) + " bytes can hold",
           "numbers of the order of the node and element counts");
  return v;
}

void expect_numbers(LineReader& r, const std::vector<std::string>& t, std::size_t first,
                    std::size_t count, const std::string& what) {
  if (t.size() < first + count)
    r.fail("expected " + std::to_string(first + count) + " numbers, found " +
               std::to_string(t.size()),
           what);
  for (std::size_t i = first; i < first + count; ++i)
    if (!is_real(t[i]))
      r.fail("'" + t[i] + "' is not a number", what);
}

// --- Gmsh .msh, version 2 (ASCII) and 4 (ASCII) ---
void check_msh(LineReader& r) {
  std::string line;
  double version = 0;
  while (r.next(line)) {
    const std::string head = tokens(line, false).empty() ? "" : tokens(line, false)[0];
    if (head == "$MeshFormat") {
      const auto t = tokens(r.need("the version line"), false);
      if (t.size() < 3 || !is_real(t[0]))
        r.fail("unreadable format line", "'VERSION FILETYPE DATASIZE', e.g. '4.1 0 8'");
      version = std::strtod(t[0].c_str(), nullptr);
      if (t[1] != "0")
        r.fail("binary Gmsh files are not checked or read", "an ASCII .msh file (FILETYPE 0)");
      if (version < 2 || version >= 5)
        r.fail("Gmsh format " + t[0], "format 2.x or 4.x");
    } else if (head == "$Nodes") {
      if (version == 0)
        r.fail("$Nodes before $MeshFormat", "a $MeshFormat section first");
      if (version < 3) {
        const long long n =
            bounded(r, first_word(r, r.need("the node count"), "the node count"), "node count");
        for (long long i = 0; i < n; ++i) {
          const auto t = tokens(r.need(std::to_string(n) + " node lines"), false);
          if (t.empty())
            r.fail("empty node line", "'ID X Y Z'");
          bounded(r, t[0], "node number");
          expect_numbers(r, t, 1, 3, "'ID X Y Z'");
        }
      } else {
        const auto h = tokens(r.need("the $Nodes header"), false);
        if (h.size() < 4)
          r.fail("short $Nodes header", "'numEntityBlocks numNodes minNodeTag maxNodeTag'");
        const long long blocks = bounded(r, h[0], "block count");
        bounded(r, h[1], "node count");
        bounded(r, h[3], "node number");
        for (long long b = 0; b < blocks; ++b) {
          const auto bh = tokens(r.need("a node block header"), false);
          if (bh.size() < 4)
            r.fail("short node block header", "'entityDim entityTag parametric numNodesInBlock'");
          const long long n = bounded(r, bh[3], "node count");
          for (long long i = 0; i < n; ++i)
            bounded(r, first_word(r, r.need("node tags"), "node tags"), "node number");
          for (long long i = 0; i < n; ++i)
            expect_numbers(r, tokens(r.need("node coordinates"), false), 0, 3, "'X Y Z'");
        }
      }
      if (tokens(r.need("$EndNodes"), false) != std::vector<std::string>{"$EndNodes"})
        r.fail("more node lines than the count says", "$EndNodes after the counted nodes");
    } else if (head == "$Elements") {
      if (version == 0)
        r.fail("$Elements before $MeshFormat", "a $MeshFormat section first");
      auto whole_numbers = [&](const std::string& l, std::size_t at_least,
                               const std::string& what) {
        const auto t = tokens(l, false);
        if (t.size() < at_least)
          r.fail("expected at least " + std::to_string(at_least) + " numbers", what);
        for (const auto& s : t)
          bounded(r, s, "number in " + what);
      };
      if (version < 3) {
        const long long n = bounded(
            r, first_word(r, r.need("the element count"), "the element count"), "element count");
        for (long long i = 0; i < n; ++i)
          whole_numbers(r.need("element lines"), 4, "'ID TYPE NTAGS TAGS... NODES...'");
      } else {
        const auto h = tokens(r.need("the $Elements header"), false);
        if (h.size() < 4)
          r.fail("short $Elements header",
                 "'numEntityBlocks numElements minElementTag maxElementTag'");
        const long long blocks = bounded(r, h[0], "block count");
        for (long long b = 0; b < blocks; ++b) {
          const auto bh = tokens(r.need("an element block header"), false);
          if (bh.size() < 4)
            r.fail("short element block header",
                   "'entityDim entityTag elementType numElementsInBlock'");
          const long long n = bounded(r, bh[3], "element count");
          for (long long i = 0; i < n; ++i)
            whole_numbers(r.need("element lines"), 2, "'TAG NODES...'");
        }
      }
      if (tokens(r.need("$EndElements"), false) != std::vector<std::string>{"$EndElements"})
        r.fail("more element lines than the count says", "$EndElements after the counted elements");
    }
  }
  if (version == 0)
    r.fail("no $MeshFormat section", "a Gmsh .msh file");
}

// --- Abaqus .inp: node and element data lines between keyword lines ---
void check_inp(LineReader& r) {
  std::string line, keyword;
  bool any_node = false;
  while (r.next(line)) {
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line.compare(first, 2, "**") == 0)
      continue;
    if (line[first] == '*') {
      keyword = line.substr(first + 1, line.find(',', first) - first - 1);
      std::transform(keyword.begin(), keyword.end(), keyword.begin(), ::toupper);
      keyword.erase(keyword.find_last_not_of(" \t") + 1);
      continue;
    }
    const auto t = tokens(line, true);
    if (keyword == "NODE") {
      if (t.size() < 3)
        r.fail("node line with " + std::to_string(t.size()) + " values",
               "'ID, X, Y[, Z]' after *Node");
      bounded(r, t[0], "node number");
      expect_numbers(r, t, 1, t.size() - 1, "'ID, X, Y[, Z]' after *Node");
      any_node = true;
    } else if (keyword == "ELEMENT") {
      for (const auto& s : t)
        bounded(r, s, "node or element number");
    } else if (keyword == "ELSET" || keyword == "NSET") {
      for (const auto& s : t) {
        long long v = 0;
        if (is_integer(s, v))
          bounded(r, s, "set member");
      }
    }
  }
  if (!any_node)
    r.fail("no *Node data", "an Abaqus input file with *Node and *Element blocks");
}

// --- legacy VTK (ASCII) unstructured grid ---
void check_vtk(LineReader& r) {
  std::string line;
  r.need("the '# vtk DataFile' line");
  r.need("the title line");
  if (tokens(r.need("ASCII"), false) != std::vector<std::string>{"ASCII"})
    r.fail("not an ASCII file", "ASCII legacy VTK (BINARY is not read)");
  // Reads `count` numbers that may span several lines.
  auto numbers = [&](long long count, bool integer, const std::string& what) {
    long long seen = 0;
    while (seen < count) {
      const auto t = tokens(r.need(std::to_string(count) + " numbers of " + what), false);
      for (const auto& s : t) {
        if (integer)
          bounded(r, s, "number in " + what);
        else if (!is_real(s))
          r.fail("'" + s + "' is not a number", what);
        ++seen;
      }
    }
    if (seen != count)
      r.fail("more numbers than the count says", what);
  };
  bool points = false, cells = false;
  while (r.next(line)) {
    const auto t = tokens(line, false);
    if (t.empty())
      continue;
    points = points || t[0] == "POINTS";
    cells = cells || t[0] == "CELLS";
    if (t[0] == "POINTS") {
      if (t.size() < 3)
        r.fail("short POINTS line", "'POINTS n double'");
      numbers(3 * bounded(r, t[1], "point count"), false, "POINTS");
    } else if (t[0] == "CELLS") {
      // n cells, each 'k i1 ... ik'. The declared list size is not used: files in the wild
      // get it wrong and readers (deal.II's too) go by the per-cell counts.
      if (t.size() < 3)
        r.fail("short CELLS line", "'CELLS n size'");
      const long long n = bounded(r, t[1], "cell count");
      bounded(r, t[2], "cell list size");
      for (long long i = 0; i < n; ++i) {
        const auto c = tokens(r.need(std::to_string(n) + " cell lines"), false);
        long long k = 0;
        if (c.empty() || !is_integer(c[0], k) || k < 1 || k > 64)
          r.fail("cell line without a node count", "'k i1 ... ik' with k from 1 to 64");
        if (static_cast<long long>(c.size()) != k + 1)
          r.fail("cell line with " + std::to_string(c.size() - 1) +
                     " node numbers, its count says " + std::to_string(k),
                 "'k i1 ... ik'");
        for (std::size_t j = 1; j < c.size(); ++j)
          bounded(r, c[j], "node number");
      }
    } else if (t[0] == "CELL_TYPES") {
      if (t.size() < 2)
        r.fail("short CELL_TYPES line", "'CELL_TYPES n'");
      numbers(bounded(r, t[1], "cell count"), true, "CELL_TYPES");
    } else if (t[0] == "CELL_DATA" || t[0] == "POINT_DATA") {
      if (t.size() < 2)
        r.fail("short " + t[0] + " line", "'" + t[0] + " n'");
      const long long n = bounded(r, t[1], "data count");
      std::string l2;
      while (r.next(l2)) { // SCALARS name type [1] / LOOKUP_TABLE default / n values
        const auto u = tokens(l2, false);
        if (u.empty())
          continue;
        if (u[0] == "LOOKUP_TABLE") {
          numbers(n, false, t[0]);
          break;
        }
        if (u[0] != "SCALARS")
          r.fail("'" + u[0] + "' in " + t[0],
                 "SCALARS name type, then LOOKUP_TABLE and the values");
      }
    }
  }
  if (!points || !cells)
    r.fail(std::string("no ") + (points ? "CELLS" : "POINTS") + " section",
           "an UNSTRUCTURED_GRID with POINTS, CELLS and CELL_TYPES");
}

} // namespace

void check_mesh_text(std::istream& in, const std::string& name, std::size_t bytes,
                     const std::string& extension) {
  LineReader reader(in, name, bytes);
  if (extension == "msh")
    check_msh(reader);
  else if (extension == "inp")
    check_inp(reader);
  else if (extension == "vtk")
    check_vtk(reader);
}

void check_mesh_file(const std::string& file, const std::string& extension) {
  if (extension == "vtu")
    return;
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw InvalidInput("Mesh file", "cannot open '" + file + "'", "a readable mesh file");
  in.seekg(0, std::ios::end);
  const auto bytes = static_cast<std::size_t>(std::max<std::streamoff>(in.tellg(), 0));
  in.seekg(0);
  check_mesh_text(in, file, bytes, extension);
}

} // namespace spinesim::fem

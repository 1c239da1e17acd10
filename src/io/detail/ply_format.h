#pragma once
// Low-level PLY reading (private to src/io): the header, and a body decoder that turns the rows
// of chosen elements into columns of doubles. Mapping columns onto HybridModel / TriangleMesh
// lives in ply_model.cpp. See docs/file-format.md for the schema and docs/decisions.md for why
// this is our own reader (precise error locations, no tinyply in Debian).
//
// Every malformed input throws linesurf::Error via throwBadInput("PATH", WHERE, WHAT), WHERE
// being "line N" (header, ascii body) or "element NAME ROW" (binary body; ROW counts from 0).
// Sizes are checked against the bytes left in the file before anything is allocated.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace linesurf::ply {

enum class Type : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class Format : uint8_t { Ascii, BinaryLittleEndian, BinaryBigEndian };

int typeSize(Type t);
bool isIntegral(Type t);
const char* typeName(Type t);  ///< canonical PLY name ("float", "uchar", ...)
/// Divisor that maps a colour channel stored as `t` onto [0, 1]: integer channels are 0..max of
/// their type, float channels 0..1. (Dividing, not multiplying by 1/255, makes k/255 exactly the
/// float the writer rounds back to k.) Shared by the whole-file and the streaming readers.
float channelScale(Type t);
/// The byte the writers store for a colour channel in [0, 1] (clamped; NaN as 0).
uint8_t colorByte(float c);

struct Property {
  std::string name;
  Type type = Type::Float32;  ///< value type (of the list items for a list)
  bool isList = false;
  Type countType = Type::UInt8;  ///< list length type
  int line = 0;                  ///< header line that declares it
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  int line = 0;  ///< header line that declares it
  /// Index of the property called `name`, or -1 (constant time: a header of many properties
  /// is read in linear time).
  int find(std::string_view name) const;
  /// Appends `p` (false, nothing added, when a property of that name exists).
  bool add(Property p);

 private:
  std::unordered_map<std::string, int> byName_;
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::vector<std::string> comments;  ///< text after "comment " (TextureFile lines included)
  std::vector<int> commentLines;      ///< header line of each comment
  size_t bodyOffset = 0;              ///< byte offset of the first body byte
  int bodyLine = 0;                   ///< line number of the first body line (ascii)
  /// Index of the element called `name`, or -1.
  int find(std::string_view name) const;
};

/// Parses the header of `bytes` (the whole file). `path` is used in error messages only.
Header parseHeader(std::string_view bytes, const std::string& path);

/// One list property of one element: row r holds values[offsets[r] .. offsets[r+1]).
struct ListColumn {
  std::vector<uint64_t> offsets;
  std::vector<double> values;
};

/// The decoded rows of one element: one column per kept scalar property, one ListColumn per kept
/// list property (both indexed like Element::properties; unkept ones stay empty).
struct ElementData {
  const Element* element = nullptr;
  std::vector<std::vector<double>> scalars;
  std::vector<ListColumn> lists;
  std::vector<uint32_t> rowLines;  ///< ascii only: the line of each row
  bool ascii = false;
  /// "line N" (ascii) or "element NAME ROW" (binary), for messages about a decoded value.
  std::string where(size_t row) const;
  const std::vector<double>* scalar(std::string_view name) const;
  const ListColumn* list(std::string_view name) const;
};

/// Which properties to keep: called once per (element, property); elements with nothing kept
/// are skipped (still checked for size).
using KeepFn = std::function<bool(const Element&, const Property&)>;

/// Decodes the body. Returns one ElementData per element (same order as header.elements).
/// Every kept float value must be finite; integer values must fit their declared type.
std::vector<ElementData> decodeBody(std::string_view bytes, const Header& header, const std::string& path,
                                    const KeepFn& keep);

}  // namespace linesurf::ply

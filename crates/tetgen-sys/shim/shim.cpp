// The extern "C" face of the vendored TetGen 1.5: flat arrays in, an opaque result handle out,
// and an error code instead of any C++ exception crossing into Rust.
//
// TetGen reports failure by `throw int` (terminatetetgen with TETLIBRARY, and the vendored
// tetgen.h turns failed asserts into `throw 2`), by std::bad_alloc from `new`, and by a non-zero
// return value when the input points span no volume. Every one of them ends up as a return code.

#include <mutex>
#include <new>
#include <string.h>

#include "tetgen.h"

namespace {

// Return codes; keep in sync with src/lib.rs.
const int OK = 0;
const int OUT_OF_MEMORY = 1;
const int INVALID_ARGUMENT = 100;
const int FLAT_INPUT = 101;
const int UNKNOWN_EXCEPTION = 102;
const int UNSUPPORTED_OUTPUT = 103;

// TetGen's `throw int` codes that have a documented meaning (see terminatetetgen in tetgen.h).
bool is_tetgen_code(int code) {
  return code == 1 || code == 2 || code == 3 || code == 4 || code == 5 || code == 10;
}

// Shewchuk's predicates keep their error bounds and TetGen's static filter (scaled to the
// current input's bounding box) in global variables set at the start of every run, so two
// runs must never overlap.
std::mutex tetgen_lock;

// TetGen copies the switches into a 1024-byte command line with strcat.
const size_t MAX_SWITCHES = 512;

template <typename T>
T *copy_array(const T *source, size_t n) {
  T *target = new T[n];
  memcpy(target, source, n * sizeof(T));
  return target;
}

bool indices_in_range(const int *indices, size_t n, int num_points) {
  for (size_t i = 0; i < n; i++) {
    if (indices[i] < 0 || indices[i] >= num_points) return false;
  }
  return true;
}

// Fills `io` (which owns and later deletes[] every array) with points, optional sizes and
// either triangle facets or tetrahedra.
void fill_points(tetgenio &io, const double *points, int num_points, const double *sizes) {
  io.firstnumber = 0;
  io.numberofpoints = num_points;
  io.pointlist = copy_array(points, 3 * (size_t) num_points);
  if (sizes != NULL) {
    io.numberofpointmtrs = 1;
    io.pointmtrlist = copy_array(sizes, (size_t) num_points);
  }
}

// Every count is set only after its array exists, so that if an allocation throws halfway,
// tetgenio's destructor frees exactly what was allocated.
void fill_facets(tetgenio &io, const int *triangles, const int *markers, int num_triangles) {
  io.facetmarkerlist = copy_array(markers, (size_t) num_triangles);
  io.facetlist = new tetgenio::facet[num_triangles];
  for (int t = 0; t < num_triangles; t++) tetgenio::init(&io.facetlist[t]);
  io.numberoffacets = num_triangles;
  for (int t = 0; t < num_triangles; t++) {
    tetgenio::facet &f = io.facetlist[t];
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.numberofpolygons = 1;
    f.polygonlist[0].vertexlist = copy_array(triangles + 3 * (size_t) t, 3);
    f.polygonlist[0].numberofvertices = 3;
  }
}

}  // namespace

struct amber_tetgen_result {
  tetgenio out;
};

extern "C" {

int amber_tetgen_tetrahedralize(const char *switches, const double *points, int num_points,
                                const int *triangles, const int *triangle_markers,
                                int num_triangles, const double *point_sizes,
                                const double *bg_points, int bg_num_points, const int *bg_tets,
                                int bg_num_tets, const double *bg_sizes,
                                amber_tetgen_result **result) {
  if (result == NULL) return INVALID_ARGUMENT;
  *result = NULL;
  if (switches == NULL || strlen(switches) > MAX_SWITCHES) return INVALID_ARGUMENT;
  if (points == NULL || num_points < 4) return INVALID_ARGUMENT;
  if (num_triangles < 0 || (num_triangles > 0 && (triangles == NULL || triangle_markers == NULL))) {
    return INVALID_ARGUMENT;
  }
  if (num_triangles > 0 && !indices_in_range(triangles, 3 * (size_t) num_triangles, num_points)) {
    return INVALID_ARGUMENT;
  }
  bool background = bg_num_points > 0;
  if (background) {
    if (bg_points == NULL || bg_tets == NULL || bg_sizes == NULL || bg_num_tets <= 0) {
      return INVALID_ARGUMENT;
    }
    if (!indices_in_range(bg_tets, 4 * (size_t) bg_num_tets, bg_num_points)) {
      return INVALID_ARGUMENT;
    }
  }

  std::lock_guard<std::mutex> guard(tetgen_lock);
  amber_tetgen_result *r = NULL;
  try {
    tetgenio in, bg;
    fill_points(in, points, num_points, point_sizes);
    if (num_triangles > 0) fill_facets(in, triangles, triangle_markers, num_triangles);
    if (background) {
      fill_points(bg, bg_points, bg_num_points, bg_sizes);
      bg.numberofcorners = 4;
      bg.numberoftetrahedra = bg_num_tets;
      bg.tetrahedronlist = copy_array(bg_tets, 4 * (size_t) bg_num_tets);
    }
    r = new amber_tetgen_result();
    int status = tetrahedralize(switches, &in, &r->out, NULL, background ? &bg : NULL);
    if (status != 0) {
      delete r;
      return FLAT_INPUT;
    }
    if (r->out.numberofcorners != 4) {
      delete r;
      return UNSUPPORTED_OUTPUT;
    }
  } catch (int code) {
    delete r;
    return is_tetgen_code(code) ? code : UNKNOWN_EXCEPTION;
  } catch (const std::bad_alloc &) {
    delete r;
    return OUT_OF_MEMORY;
  } catch (...) {
    delete r;
    return UNKNOWN_EXCEPTION;
  }
  *result = r;
  return OK;
}

int amber_tetgen_num_points(const amber_tetgen_result *r) { return r->out.numberofpoints; }
const double *amber_tetgen_points(const amber_tetgen_result *r) { return r->out.pointlist; }
int amber_tetgen_num_tets(const amber_tetgen_result *r) { return r->out.numberoftetrahedra; }
const int *amber_tetgen_tets(const amber_tetgen_result *r) { return r->out.tetrahedronlist; }
int amber_tetgen_num_faces(const amber_tetgen_result *r) { return r->out.numberoftrifaces; }
const int *amber_tetgen_faces(const amber_tetgen_result *r) { return r->out.trifacelist; }
const int *amber_tetgen_face_markers(const amber_tetgen_result *r) {
  return r->out.trifacemarkerlist;
}

void amber_tetgen_free(amber_tetgen_result *r) { delete r; }

}  // extern "C"

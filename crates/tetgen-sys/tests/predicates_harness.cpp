// Exactly coplanar points (on the plane z = 2x) whose coordinate differences are not
// representable, so orient3d runs its adaptive stages to the last one, where the expansion
// sums once read past their inputs. Built with AddressSanitizer by `predicates_asan.rs`; exits
// non-zero if a coplanar quadruple is not reported as exactly coplanar.
#include <cmath>
#include <cstdio>
#include <cstdlib>

int exactinit(int, int, int, double, double, double);
double orient3d(double*, double*, double*, double*);
double insphere(double*, double*, double*, double*, double*);

static double uniform() { return std::rand() / (double)RAND_MAX; }
// Magnitudes from 1 down to 1e-19, so differences of coordinates round.
static double mixed() { return uniform() * std::pow(10.0, -(std::rand() % 20)); }

int main() {
  std::srand(1);
  exactinit(0, 0, 0, 1, 1, 1);
  int wrong = 0;
  double ignored = 0;
  for (int n = 0; n < 100000; n++) {
    double p[5][3];
    for (auto& q : p) {
      q[0] = mixed();
      q[1] = mixed();
      q[2] = 2 * q[0];
    }
    if (orient3d(p[0], p[1], p[2], p[3]) != 0.0) wrong++;
    ignored += insphere(p[0], p[1], p[2], p[3], p[4]);
  }
  std::printf("%d coplanar quadruples not found coplanar (insphere sum %g)\n", wrong, ignored);
  return wrong == 0 ? 0 : 1;
}

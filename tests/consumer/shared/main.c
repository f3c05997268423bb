// Checks the shared library frequency.c: 1 kg on 100 N/m swings at sqrt(k / m) / (2 pi) =
// 1.5915494309189535 Hz, in each of its three directions (a zero-length spring), to round-off.
#include <math.h>
#include <stdio.h>

double frequency_of(double mass, double stiffness);

int main(void)
{
	const double f = frequency_of(1.0, 100.0), expected = 10.0 / (2.0 * acos(-1.0));
	if (!(fabs(f - expected) <= 1e-12 * expected)) {
		fprintf(stderr, "frequency_of(1 kg, 100 N/m) = %.17g Hz, expected %.17g Hz\n", f, expected);
		return 1;
	}
	return 0;
}

// Checks frequency.c built as a module, a plug-in loaded at run time (FREQUENCY_PLUGIN names its
// file): 1 kg on 100 N/m swings at sqrt(k / m) / (2 pi) = 1.5915494309189535 Hz, to round-off.
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>

int main(void)
{
	void* plugin = dlopen(FREQUENCY_PLUGIN, RTLD_NOW | RTLD_LOCAL);
	if (plugin == NULL) {
		fprintf(stderr, "dlopen: %s\n", dlerror());
		return 1;
	}
	double (*frequency_of)(double, double);
	*(void**)&frequency_of = dlsym(plugin, "frequency_of");
	if (frequency_of == NULL) {
		fprintf(stderr, "dlsym: %s\n", dlerror());
		dlclose(plugin);
		return 1;
	}
	const double f = frequency_of(1.0, 100.0), expected = 10.0 / (2.0 * acos(-1.0));
	dlclose(plugin);
	if (!(fabs(f - expected) <= 1e-12 * expected)) {
		fprintf(stderr, "frequency_of(1 kg, 100 N/m) = %.17g Hz, expected %.17g Hz\n", f, expected);
		return 1;
	}
	return 0;
}

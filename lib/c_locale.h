// The C locale for the calling thread, for the span of a call: text written or read there has a
// '.' whatever LC_NUMERIC the program chose (under de_DE printf writes 0.5 as "0,5", which is not
// JSON, and a message's list "n = 0,5, m = 2" reads two ways). setlocale() is process-wide;
// uselocale() switches the calling thread only. glibc's "C" locale object is static (newlocale
// allocates nothing for it, freelocale does nothing), so entering it fails only in principle.
//
//   sm_c_locale_scope scope = sm_enter_c_locale();
//   if (!sm_c_locale_entered(scope)) { ... out of memory ... }
//   ... printf, strtod, json_loadb, json_dumps ...
//   sm_leave_c_locale(scope);
#pragma once

#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#error "c_locale.h needs _POSIX_C_SOURCE 200809L (newlocale, uselocale) defined before any include"
#endif

#include <locale.h>
#include <stdbool.h>

typedef struct sm_c_locale_scope {
	locale_t c, previous;
} sm_c_locale_scope;

static inline sm_c_locale_scope sm_enter_c_locale(void)
{
	sm_c_locale_scope scope = {newlocale(LC_ALL_MASK, "C", (locale_t)0), (locale_t)0};
	if (scope.c != (locale_t)0)
		scope.previous = uselocale(scope.c);
	return scope;
}

static inline bool sm_c_locale_entered(sm_c_locale_scope scope)
{
	return scope.c != (locale_t)0;
}

// Back to the thread's locale before sm_enter_c_locale; nothing when it was not entered.
static inline void sm_leave_c_locale(sm_c_locale_scope scope)
{
	if (scope.c != (locale_t)0) {
		uselocale(scope.previous);
		freelocale(scope.c);
	}
}

/* The lock around FFTW's planner (fft.h). */
#include "bkfront/fft.h"

#include <pthread.h>

static pthread_mutex_t planner = PTHREAD_MUTEX_INITIALIZER;

void bkf_fft_lock(void) { pthread_mutex_lock(&planner); }

void bkf_fft_unlock(void) { pthread_mutex_unlock(&planner); }

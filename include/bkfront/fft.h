/* FFTW's planner, shared by the threads of a process.
 *
 * FFTW keeps one planner per process: fftw_plan_* and fftw_destroy_plan
 * must never run in two threads at once, while fftw_execute* on distinct
 * plans (or on one plan with the new-array calls) may.  Every plan the
 * library makes or destroys is made under this one lock, so library calls
 * in several threads at once are safe.  A host program that plans with FFTW
 * itself in other threads while library calls run takes the same lock
 * around its planning. */
#ifndef BKFRONT_FFT_H
#define BKFRONT_FFT_H

#ifdef __cplusplus
extern "C" {
#endif

void bkf_fft_lock(void);
void bkf_fft_unlock(void);

#ifdef __cplusplus
}
#endif

#endif

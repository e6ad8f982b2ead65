; accelcal -- start-up for H8/300H programs run on GNU's H8 simulator (normal
; mode, h8300-hms-gcc -mh -mn): stack pointer, .bss cleared (the simulator's
; memory is zero already, a real part's is not), main, then the simulator's
; exit sequence with main's return value as the exit status.
; The exit sequence (_h8sim_exit, status in r0) is: r0 = status << 8 with a
; zero low byte, r1 = 0xDEAD, r2 = 0xBEEF, sleep.  A stray sleep (other
; registers) stops the simulator with SIGTRAP instead, i.e. a failure.
	.h8300hn
	.section .text
	.global _start
	.global _h8sim_exit
_start:
	mov.w	#_stack, r7
	mov.w	#_bss_start, r0
	mov.w	#_end, r1
	sub.w	r2, r2
.Lclear:
	cmp.w	r1, r0
	bhs	.Lcleared
	mov.b	r2l, @er0
	adds	#1, er0
	bra	.Lclear
.Lcleared:
	jsr	@_main
_h8sim_exit:
	mov.b	r0l, r0h
	sub.b	r0l, r0l
	mov.w	#0xdead, r1
	mov.w	#0xbeef, r2
	sleep
.Lstray:
	bra	.Lstray

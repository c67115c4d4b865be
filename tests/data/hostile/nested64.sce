~ nested64.sce - hostile: 64 nested definitions, each two overlapping
  instances of the one before (the second turned by 1 degree), so a1's
  sphere is drawn 2^63 times. Every limit is met and it builds at once,
  but the camera sits close, so every eye ray meets the cluster and visits
  all 2^63 instances (their bounds overlap: none is culled): no pixel ever
  finishes unless cancelled (tests/unit/test_cancel.c). ~
camera look-from (0 0 2.5) look-at (0 0 0) ;
image xsize 8 ysize 6 ;
light position (5 5 10) ;
define
object name a1 object sphere centre (.1 0 0) ; ; ;
object name a2 object a1 ; ; object a1 z-rotate 1 ; ; ;
object name a3 object a2 ; ; object a2 z-rotate 1 ; ; ;
object name a4 object a3 ; ; object a3 z-rotate 1 ; ; ;
object name a5 object a4 ; ; object a4 z-rotate 1 ; ; ;
object name a6 object a5 ; ; object a5 z-rotate 1 ; ; ;
object name a7 object a6 ; ; object a6 z-rotate 1 ; ; ;
object name a8 object a7 ; ; object a7 z-rotate 1 ; ; ;
object name a9 object a8 ; ; object a8 z-rotate 1 ; ; ;
object name a10 object a9 ; ; object a9 z-rotate 1 ; ; ;
object name a11 object a10 ; ; object a10 z-rotate 1 ; ; ;
object name a12 object a11 ; ; object a11 z-rotate 1 ; ; ;
object name a13 object a12 ; ; object a12 z-rotate 1 ; ; ;
object name a14 object a13 ; ; object a13 z-rotate 1 ; ; ;
object name a15 object a14 ; ; object a14 z-rotate 1 ; ; ;
object name a16 object a15 ; ; object a15 z-rotate 1 ; ; ;
object name a17 object a16 ; ; object a16 z-rotate 1 ; ; ;
object name a18 object a17 ; ; object a17 z-rotate 1 ; ; ;
object name a19 object a18 ; ; object a18 z-rotate 1 ; ; ;
object name a20 object a19 ; ; object a19 z-rotate 1 ; ; ;
object name a21 object a20 ; ; object a20 z-rotate 1 ; ; ;
object name a22 object a21 ; ; object a21 z-rotate 1 ; ; ;
object name a23 object a22 ; ; object a22 z-rotate 1 ; ; ;
object name a24 object a23 ; ; object a23 z-rotate 1 ; ; ;
object name a25 object a24 ; ; object a24 z-rotate 1 ; ; ;
object name a26 object a25 ; ; object a25 z-rotate 1 ; ; ;
object name a27 object a26 ; ; object a26 z-rotate 1 ; ; ;
object name a28 object a27 ; ; object a27 z-rotate 1 ; ; ;
object name a29 object a28 ; ; object a28 z-rotate 1 ; ; ;
object name a30 object a29 ; ; object a29 z-rotate 1 ; ; ;
object name a31 object a30 ; ; object a30 z-rotate 1 ; ; ;
object name a32 object a31 ; ; object a31 z-rotate 1 ; ; ;
object name a33 object a32 ; ; object a32 z-rotate 1 ; ; ;
object name a34 object a33 ; ; object a33 z-rotate 1 ; ; ;
object name a35 object a34 ; ; object a34 z-rotate 1 ; ; ;
object name a36 object a35 ; ; object a35 z-rotate 1 ; ; ;
object name a37 object a36 ; ; object a36 z-rotate 1 ; ; ;
object name a38 object a37 ; ; object a37 z-rotate 1 ; ; ;
object name a39 object a38 ; ; object a38 z-rotate 1 ; ; ;
object name a40 object a39 ; ; object a39 z-rotate 1 ; ; ;
object name a41 object a40 ; ; object a40 z-rotate 1 ; ; ;
object name a42 object a41 ; ; object a41 z-rotate 1 ; ; ;
object name a43 object a42 ; ; object a42 z-rotate 1 ; ; ;
object name a44 object a43 ; ; object a43 z-rotate 1 ; ; ;
object name a45 object a44 ; ; object a44 z-rotate 1 ; ; ;
object name a46 object a45 ; ; object a45 z-rotate 1 ; ; ;
object name a47 object a46 ; ; object a46 z-rotate 1 ; ; ;
object name a48 object a47 ; ; object a47 z-rotate 1 ; ; ;
object name a49 object a48 ; ; object a48 z-rotate 1 ; ; ;
object name a50 object a49 ; ; object a49 z-rotate 1 ; ; ;
object name a51 object a50 ; ; object a50 z-rotate 1 ; ; ;
object name a52 object a51 ; ; object a51 z-rotate 1 ; ; ;
object name a53 object a52 ; ; object a52 z-rotate 1 ; ; ;
object name a54 object a53 ; ; object a53 z-rotate 1 ; ; ;
object name a55 object a54 ; ; object a54 z-rotate 1 ; ; ;
object name a56 object a55 ; ; object a55 z-rotate 1 ; ; ;
object name a57 object a56 ; ; object a56 z-rotate 1 ; ; ;
object name a58 object a57 ; ; object a57 z-rotate 1 ; ; ;
object name a59 object a58 ; ; object a58 z-rotate 1 ; ; ;
object name a60 object a59 ; ; object a59 z-rotate 1 ; ; ;
object name a61 object a60 ; ; object a60 z-rotate 1 ; ; ;
object name a62 object a61 ; ; object a61 z-rotate 1 ; ; ;
object name a63 object a62 ; ; object a62 z-rotate 1 ; ; ;
object name a64 object a63 ; ; object a63 z-rotate 1 ; ; ;
;
object a64 ; ;

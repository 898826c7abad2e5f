--  The extern functions of callorder.rcs in Ada: the journal of callorder_impl.py.

package body callorder_0_Externs is

   S : Integer_64 := 0;

   function Mix (V : Integer_64) return Integer_64 is
   begin
      S := (S * 31 + V) mod 1000003;
      return S;
   end Mix;

   function Low (V : Integer_64) return Integer_64 is
     (Integer_64 (Unsigned_64'Mod (V) and 1023));

   function F_0_t_i32 (X06b : Integer_32) return Integer_32 is
     (Integer_32 (Mix (Integer_64 (X06b))));

   function F_0_t_f64 (x : F64; X06b : Integer_32) return F64 is
     (x + F64 (Mix (Integer_64 (X06b))));

   function F_0_t_bool (X06b : Integer_32) return Boolean is
     (Mix (Integer_64 (X06b)) mod 2 = 1);

   function F_0_t_mode (X06d : T_0_X04d6f6465; X06b : Integer_32) return T_0_X04d6f6465 is
     (T_0_X04d6f6465 (Mix (Integer_64 (X06b) * 4 + Integer_64 (X06d)) mod 3));

   function F_0_t_pt (p : T_0_Pt; X06b : Integer_32) return T_0_Pt is
      V : constant Integer_64 := Mix (Integer_64 (X06b) * 7 + Low (Integer_64 (p.X061)));
   begin
      return (X061 => Integer_32 (V mod 100), X062 => p.X062 + 1.0);
   end F_0_t_pt;

   function F_0_t_dur (d : Integer_64; X06b : Integer_32) return Integer_64 is
     (d + Mix (Integer_64 (X06b)) * 1_000_000);

   function F_0_t_u32 (u : Unsigned_32; X06b : Integer_32) return Unsigned_32 is
     (u + Unsigned_32 (Mix (Integer_64 (X06b))));

   function F_0_t_i64 (X076 : Integer_64; X06b : Integer_32) return Integer_64 is
     (Mix (Integer_64 (X06b)) * 1024 + Low (X076));

   function F_0_t_arr (xs : A_0_I32_0_3; X06b : Integer_32) return Integer_32 is
      V : Integer_64 := Mix (Integer_64 (X06b));
   begin
      for X of xs loop
         V := Mix (Low (Integer_64 (X)));
      end loop;
      return Integer_32 (V);
   end F_0_t_arr;

   function F_0_pair (X061 : Integer_32; X062 : Integer_32) return Integer_32 is
      V : Integer_64 := Mix (Low (Integer_64 (X061)));
   begin
      V := Mix (Low (Integer_64 (X062)));
      return Integer_32 (V);
   end F_0_pair;

   function F_0_peek return Integer_32 is (Integer_32 (S));

end callorder_0_Externs;

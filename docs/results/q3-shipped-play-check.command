scripts/maps-shipped-leaf.sh 1 45 --play-space aggressor am_lavactfxl am_underworks2 ctf_gate1 czest3ctf hydronex2 kaos2 oa_bases3p3ta oa_dm1 oa_dm6 oa_minia oa_spirit3 ps37ctf pul1duel-oa
